// The rescale plan on its own, without an estimate: it lists and validates
// every artefact once, makes every refusal the commit could make (the
// already-rescaled rule in each mode, an interrupted commit in each mode,
// truncated and unknown files), reads a dry run over an interrupted commit
// from the files recovery will leave, and its execution refuses when a
// planned file changed meanwhile.
#include "dpsfm/colmap/rescale/rescale_plan.h"

#include <chrono>
#include <filesystem>
#include <map>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "dpsfm/colmap/rescale/rescale.h"
#include "dpsfm/colmap/rescale/transaction.h"
#include "dpsfm/colmap/util/input_error.h"
#include "tests/colmap/rescale/workspace_fixture.h"
#include "tests/test_utils.h"

namespace dpsfm {
namespace {

namespace fs = std::filesystem;
using test::MakeWorkspace;
using test::ReadTextFile;
using test::SnapshotTree;
using test::TempDir;
using test::WriteTextFile;

RescalePlanOptions Options(RescaleMode mode, const std::string& root) {
  RescalePlanOptions options;
  options.mode = mode;
  options.workspace_root = root;
  return options;
}

// The message of the InputError `plan` throws ("" if it throws none).
std::string RefusalOf(const RescalePlanOptions& options) {
  try {
    PlanRescale(options);
  } catch (const InputError& error) {
    return error.what();
  }
  return "";
}

bool Contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

// A commit interrupted after its first `renames` renames, built by hand the
// way CommitTransaction leaves it: every artefact and the record staged
// (rescaled by `scale`), the journal listing them (record last), and the
// first `renames` staged files moved over their targets.
void InterruptCommit(const std::string& root, double scale, size_t renames) {
  const std::vector<Artefact> artefacts = ListArtefactsToRescale(root);
  const fs::path canonical = fs::canonical(root);
  std::vector<std::string> targets;
  for (const Artefact& artefact : artefacts) {
    WriteRescaledArtefact(artefact, scale, StagedPath(artefact.path));
    targets.push_back(
        fs::canonical(artefact.path).lexically_relative(canonical).string());
  }
  ScaleRecord record;
  record.Append(scale, {"test"}, "test");
  WriteTextFile(StagedPath(ScaleRecordPath(root)), record.ToJson());
  targets.push_back(kScaleRecordFileName);
  nlohmann::json journal;
  journal["version"] = 1;
  journal["targets"] = targets;
  WriteTextFile((fs::path(root) / kJournalFileName).string(), journal.dump());
  for (size_t i = 0; i < renames; ++i) {
    fs::rename(StagedPath(artefacts[i].path), artefacts[i].path);
  }
}

TEST(RescalePlan, ListsEveryArtefactOnceAndStampsWhatItRead) {
  TempDir dir;
  const std::string root = dir / "ws";
  MakeWorkspace(root);
  const RescalePlan plan = PlanRescale(Options(RescaleMode::kInPlace, root));
  const std::vector<Artefact> listed = ListArtefactsToRescale(root);
  ASSERT_EQ(plan.artefacts.size(), listed.size());
  for (size_t i = 0; i < listed.size(); ++i) {
    EXPECT_EQ(plan.artefacts[i].path, listed[i].path);
  }
  // 6 depth maps (3 geometric, 3 photometric; normal maps are not metric)
  // and fused.ply.
  EXPECT_TRUE(Contains(plan.Summary(), "6 depth maps, 1 PLY"))
      << plan.Summary();
  // Every artefact, the record and the journal (both absent).
  ASSERT_EQ(plan.stamps.size(), listed.size() + 2);
  EXPECT_FALSE(plan.stamps[listed.size()].exists);
  EXPECT_FALSE(plan.stamps[listed.size() + 1].exists);
  EXPECT_TRUE(plan.stamps[0].exists);
  EXPECT_GT(plan.stamps[0].size, 0u);
  EXPECT_TRUE(plan.warnings.empty());
  EXPECT_TRUE(plan.refusal.empty());
  EXPECT_FALSE(plan.interrupted());
}

TEST(RescalePlan, AlreadyRescaledIsOneRuleInEveryMode) {
  TempDir dir;
  const std::string root = dir / "ws";
  MakeWorkspace(root);
  RescaleWorkspaceInPlace(root, 0.5, RescaleWorkspaceOptions());
  const auto tree = SnapshotTree(root);

  const std::string in_place = RefusalOf(Options(RescaleMode::kInPlace, root));
  EXPECT_TRUE(Contains(in_place, "already rescaled")) << in_place;
  EXPECT_TRUE(Contains(in_place, "cumulative scale 0.5")) << in_place;
  EXPECT_TRUE(Contains(in_place, "--force 1")) << in_place;

  RescalePlanOptions copy = Options(RescaleMode::kCopy, root);
  copy.output_path = dir / "copy";
  const std::string copied = RefusalOf(copy);
  EXPECT_TRUE(Contains(copied, "already rescaled")) << copied;
  EXPECT_FALSE(fs::exists(dir / "copy"));

  const RescalePlan dry = PlanRescale(Options(RescaleMode::kDryRun, root));
  ASSERT_EQ(dry.warnings.size(), 1u);
  EXPECT_TRUE(Contains(dry.warnings[0], "already rescaled"));
  EXPECT_TRUE(dry.record.IsRescaled());

  RescalePlanOptions forced = Options(RescaleMode::kInPlace, root);
  forced.force = true;
  EXPECT_EQ(RefusalOf(forced), "");
  copy.force = true;
  EXPECT_EQ(RefusalOf(copy), "");
  EXPECT_TRUE(SnapshotTree(root) == tree) << "planning wrote to the workspace";
}

TEST(RescalePlan, InvalidArtefactsAreRefusedByThePlanNamingTheFile) {
  TempDir dir;
  const std::string root = dir / "ws";
  MakeWorkspace(root);
  const std::string fused = root + "/fused.ply";
  const std::string bytes = ReadTextFile(fused);
  WriteTextFile(fused, bytes.substr(0, bytes.size() - 10));
  const std::string refusal = RefusalOf(Options(RescaleMode::kInPlace, root));
  EXPECT_TRUE(Contains(refusal, "fused.ply")) << refusal;
  EXPECT_TRUE(Contains(refusal, "truncated")) << refusal;
  // A dry run says what a rescale in place would refuse, and goes on.
  const RescalePlan dry = PlanRescale(Options(RescaleMode::kDryRun, root));
  EXPECT_EQ(dry.refusal, refusal);
  WriteTextFile(fused, bytes);

  // A depth map is checked by its header against its size.
  const std::string depth = root + "/stereo/depth_maps/image1.geometric.bin";
  const std::string depth_bytes = ReadTextFile(depth);
  WriteTextFile(depth, depth_bytes + "xyzw");
  const std::string bad_depth = RefusalOf(Options(RescaleMode::kInPlace, root));
  EXPECT_TRUE(Contains(bad_depth, "image1.geometric.bin")) << bad_depth;
  EXPECT_TRUE(Contains(bad_depth, "does not match its header")) << bad_depth;
  WriteTextFile(depth, depth_bytes);

  // A file of unknown treatment in a model folder.
  WriteTextFile(root + "/sparse/model.nvm", "NVM_V3\n");
  const std::string unknown = RefusalOf(Options(RescaleMode::kInPlace, root));
  EXPECT_TRUE(Contains(unknown, "model.nvm")) << unknown;
  fs::remove(root + "/sparse/model.nvm");
  EXPECT_EQ(RefusalOf(Options(RescaleMode::kInPlace, root)), "");
}

TEST(RescalePlan, CopyTargetsAreCheckedBeforeTheEstimate) {
  TempDir dir;
  const std::string root = dir / "ws";
  MakeWorkspace(root);
  RescalePlanOptions copy = Options(RescaleMode::kCopy, root);
  copy.output_path = root;
  EXPECT_TRUE(Contains(RefusalOf(copy), "is the input itself"));
  copy.output_path = root + "/sub";
  EXPECT_TRUE(Contains(RefusalOf(copy), "lies inside the input"));
  WriteTextFile(dir / "full/file", "x");
  copy.output_path = dir / "full";
  EXPECT_TRUE(Contains(RefusalOf(copy), "already exists and is not empty"));
  copy.output_path = dir / "fine";
  EXPECT_EQ(RefusalOf(copy), "");
}

TEST(RescalePlan, InterruptedCommitInEveryMode) {
  TempDir dir;
  const std::string root = dir / "ws";
  MakeWorkspace(root);
  // The model's images.bin and points3D.bin are new, everything else waits
  // staged.
  InterruptCommit(root, 2.0, 2);
  const auto tree = SnapshotTree(root);

  const std::string in_place = RefusalOf(Options(RescaleMode::kInPlace, root));
  EXPECT_TRUE(Contains(in_place, "interrupted rescale")) << in_place;
  RescalePlanOptions copy = Options(RescaleMode::kCopy, root);
  copy.output_path = dir / "copy";
  const std::string copied = RefusalOf(copy);
  EXPECT_TRUE(Contains(copied, "interrupted rescale")) << copied;
  EXPECT_TRUE(Contains(copied, "once in place")) << copied;
  EXPECT_FALSE(fs::exists(dir / "copy"));

  const RescalePlan dry = PlanRescale(Options(RescaleMode::kDryRun, root));
  EXPECT_TRUE(dry.interrupted());
  ASSERT_FALSE(dry.warnings.empty());
  EXPECT_TRUE(Contains(dry.warnings[0], "interrupted rescale"));
  // The staged record says the workspace will be in metres.
  EXPECT_TRUE(dry.record.IsRescaled());
  EXPECT_TRUE(SnapshotTree(root) == tree) << "planning wrote to the workspace";

  // What the dry run reads for each file is what recovery leaves there.
  std::map<std::string, std::string> read;
  for (const Artefact& artefact : dry.artefacts) {
    read[artefact.path] = ReadTextFile(dry.ReadPath(artefact.path));
  }
  EXPECT_EQ(dry.StagedFilesRead().size(), dry.artefacts.size() - 2 + 1);
  RecoverInterruptedCommit(root);
  ASSERT_FALSE(read.empty());
  for (const auto& entry : read) {
    EXPECT_TRUE(ReadTextFile(entry.first) == entry.second) << entry.first;
  }
}

TEST(RescalePlan, ExecutionRefusesWhenAPlannedFileChanged) {
  TempDir dir;
  const std::string root = dir / "ws";
  MakeWorkspace(root);
  const RescalePlan plan = PlanRescale(Options(RescaleMode::kInPlace, root));
  // Another value in the last depth: the same size, a new modification time
  // (file times tick coarsely: a few milliseconds apart).
  std::this_thread::sleep_for(std::chrono::milliseconds(50));
  const std::string depth = root + "/stereo/depth_maps/image2.geometric.bin";
  std::string changed = ReadTextFile(depth);
  changed[changed.size() - 1] ^= 0x01;
  WriteTextFile(depth, changed);
  const auto tree = SnapshotTree(root);
  try {
    ExecuteRescalePlan(plan, 2.0, RescaleProvenance());
    ADD_FAILURE() << "a changed file was rescaled";
  } catch (const InputError& error) {
    EXPECT_TRUE(Contains(error.what(), "image2.geometric.bin")) << error.what();
    EXPECT_TRUE(Contains(error.what(), "nothing was written")) << error.what();
  }
  EXPECT_TRUE(SnapshotTree(root) == tree);

  // A record that appeared meanwhile (another run committed) refuses too.
  const RescalePlan again = PlanRescale(Options(RescaleMode::kInPlace, root));
  ScaleRecord record;
  record.Append(3.0, {}, "other");
  WriteTextFile(ScaleRecordPath(root), record.ToJson());
  EXPECT_THROW(ExecuteRescalePlan(again, 2.0, RescaleProvenance()), InputError);
  fs::remove(ScaleRecordPath(root));

  // Unchanged, the plan executes as it stands.
  const RescalePlan fresh = PlanRescale(Options(RescaleMode::kInPlace, root));
  const RescaleWorkspaceResult result =
      ExecuteRescalePlan(fresh, 2.0, RescaleProvenance());
  EXPECT_EQ(result.rescaled_files.size(), fresh.artefacts.size());
  EXPECT_EQ(ReadScaleRecord(root).CumulativeScale(), 2.0);
  EXPECT_THROW(
      ExecuteRescalePlan(PlanRescale(Options(RescaleMode::kDryRun, root)),
                         2.0,
                         RescaleProvenance()),
      std::logic_error);
}

}  // namespace
}  // namespace dpsfm
