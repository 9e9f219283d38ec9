// All-or-nothing commits: a crash after any number of renames leaves every
// file fully old or fully new and recovery finishes the job; staged files
// without a journal roll back; the scale record composes; copies are never
// half there.
#include "dpsfm/colmap/rescale/transaction.h"

#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <functional>
#include <map>
#include <set>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "colmap/math/random.h"
#include "colmap/scene/reconstruction.h"
#include "colmap/scene/synthetic.h"
#include "dpsfm/colmap/io/workspace.h"
#include "dpsfm/colmap/rescale/rescale.h"
#include "dpsfm/colmap/rescale/rescale_plan.h"
#include "dpsfm/colmap/util/colmap_compat.h"
#include "tests/colmap/rescale/workspace_fixture.h"
#include "tests/test_utils.h"

namespace dpsfm {
namespace {

namespace fs = std::filesystem;
using test::MakeWorkspace;
using test::ReadTextFile;
using test::SnapshotTree;
using test::TempDir;
using test::WriteModel;
using test::WriteTextFile;

using Tree = std::map<std::string, std::string>;

constexpr double kScale = 0.0412;

void CopyTree(const std::string& from, const std::string& to) {
  for (const auto& entry : SnapshotTree(from)) {
    if (entry.first.back() == '/') {
      fs::create_directories(to + "/" + entry.first);
    } else {
      WriteTextFile(to + "/" + entry.first, entry.second);
    }
  }
}

Tree WithoutRecord(Tree tree) {
  tree.erase(kScaleRecordFileName);
  return tree;
}

bool IsTransactionFile(const std::string& relative) {
  const std::string suffix = kStagedSuffix;
  return (relative.size() > suffix.size() &&
          relative.compare(
              relative.size() - suffix.size(), suffix.size(), suffix) == 0) ||
         relative == kJournalFileName || relative == kStagingListFileName;
}

// Runs `body` in a child process (so std::_Exit from fault injection does
// not end the test) and returns its exit code, or -1 if it was killed.
int RunInChild(const std::function<void()>& body,
               const char* fault_after = nullptr) {
  const pid_t pid = fork();
  if (pid == 0) {
    if (fault_after != nullptr) {
      setenv(kFaultInjectCommitEnv, fault_after, 1);
    }
    try {
      body();
    } catch (...) {
      _exit(3);
    }
    _exit(0);
  }
  int status = 0;
  waitpid(pid, &status, 0);
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

// old/new trees of one workspace, the new one made by a clean run on a copy.
struct Fixture {
  TempDir dir;
  std::string root = dir / "ws";
  Tree old_tree;
  Tree new_tree;  // without the record (it holds a time)
  size_t num_renames = 0;

  Fixture() {
    MakeWorkspace(root);
    old_tree = SnapshotTree(root);
    const std::string twin = dir / "twin";
    CopyTree(root, twin);
    RescaleWorkspaceInPlace(twin, kScale, RescaleWorkspaceOptions());
    new_tree = WithoutRecord(SnapshotTree(twin));
    num_renames = ListArtefactsToRescale(root).size() + 1;  // + the record
  }
};

TEST(CommitTransaction, KillAfterEveryRenameRecoversToFullyNew) {
  Fixture reference;
  // The model in both formats (with rigs and frames on COLMAP 4), 6 depth
  // maps, fused.ply, the record.
  ASSERT_EQ((kWriterWritesRigsAndFrames ? 8u : 4u) + 6u + 1u + 1u,
            reference.num_renames);
  ASSERT_NE(reference.old_tree.at("fused.ply"),
            reference.new_tree.at("fused.ply"));
  for (size_t k = 0; k <= reference.num_renames; ++k) {
    SCOPED_TRACE("fault after rename " + std::to_string(k));
    TempDir dir;
    const std::string root = dir / "ws";
    CopyTree(reference.root, root);
    const std::string k_text = std::to_string(k);
    const int code = RunInChild(
        [&] {
          RescaleWorkspaceInPlace(root, kScale, RescaleWorkspaceOptions());
        },
        k_text.c_str());
    ASSERT_EQ(kFaultInjectExitCode, code);

    // Right after the crash: every workspace file is fully old or fully new,
    // exactly k of them are new, and the journal says what to finish.
    const Tree crashed = SnapshotTree(root);
    EXPECT_TRUE(crashed.count(kJournalFileName));
    size_t num_new = 0;
    for (const auto& entry : crashed) {
      if (IsTransactionFile(entry.first)) continue;
      if (entry.first == kScaleRecordFileName) {
        ++num_new;  // renamed last: only after the others
        EXPECT_EQ(reference.num_renames, k);
        continue;
      }
      const bool is_old = reference.old_tree.count(entry.first) &&
                          reference.old_tree.at(entry.first) == entry.second;
      const bool is_new = reference.new_tree.at(entry.first) == entry.second;
      EXPECT_TRUE(is_old || is_new) << entry.first << " is half written";
      if (is_new && !is_old) ++num_new;
    }
    EXPECT_EQ(k, num_new);
    for (const auto& entry : reference.old_tree) {
      EXPECT_TRUE(crashed.count(entry.first)) << entry.first << " vanished";
    }

    const RecoveryReport report = RecoverInterruptedCommit(root);
    EXPECT_EQ(RecoveryReport::Action::kRolledForward, report.action);
    EXPECT_EQ(reference.num_renames - k, report.completed.size());
    EXPECT_NE(std::string::npos, report.Describe().find("finished"));
    const Tree recovered = SnapshotTree(root);
    EXPECT_EQ(reference.new_tree, WithoutRecord(recovered));
    const ScaleRecord record = ReadScaleRecord(root);
    ASSERT_EQ(1u, record.entries.size());
    EXPECT_EQ(kScale, record.entries[0].cumulative_scale);

    // Recovery is idempotent.
    EXPECT_EQ(RecoveryReport::Action::kNothing,
              RecoverInterruptedCommit(root).action);
    EXPECT_EQ(recovered, SnapshotTree(root));
  }
}

TEST(CommitTransaction, WithoutFaultItCompletesAndLeavesNoTraces) {
  Fixture reference;
  TempDir dir;
  const std::string root = dir / "ws";
  CopyTree(reference.root, root);
  // A fault point beyond the last rename never fires.
  const std::string beyond = std::to_string(reference.num_renames + 1);
  EXPECT_EQ(0,
            RunInChild(
                [&] {
                  RescaleWorkspaceInPlace(
                      root, kScale, RescaleWorkspaceOptions());
                },
                beyond.c_str()));
  const Tree tree = SnapshotTree(root);
  EXPECT_EQ(reference.new_tree, WithoutRecord(tree));
  for (const auto& entry : tree) {
    EXPECT_FALSE(IsTransactionFile(entry.first)) << entry.first;
  }
}

TEST(CommitTransaction, StagedWithoutJournalRollsBack) {
  Fixture reference;
  const std::string outside = reference.dir / "outside_model";
  WriteModel(outside, true, false);
  const Tree outside_before = SnapshotTree(outside);

  // The process dies after staging everything, before the journal.
  EXPECT_EQ(0, RunInChild([&] {
              CommitTransaction transaction(reference.root);
              for (const Artefact& artefact :
                   ListArtefactsToRescale(reference.root, {outside})) {
                transaction.Stage(artefact.path, [&](const std::string& s) {
                  WriteRescaledArtefact(artefact, kScale, s);
                });
              }
              transaction.StageContents(ScaleRecordPath(reference.root), "{}");
              _exit(0);  // no destructor, no commit: a crash
            }));
  const Tree crashed = SnapshotTree(reference.root);
  EXPECT_GT(crashed.size(), reference.old_tree.size());
  EXPECT_TRUE(crashed.count("sparse/images.bin.dpsfm-staged"));
  EXPECT_TRUE(crashed.count(kStagingListFileName));
  EXPECT_TRUE(fs::exists(outside + "/images.bin.dpsfm-staged"));

  const RecoveryReport report = RecoverInterruptedCommit(reference.root);
  EXPECT_EQ(RecoveryReport::Action::kRolledBack, report.action);
  EXPECT_TRUE(report.completed.empty());
  EXPECT_EQ(reference.old_tree, SnapshotTree(reference.root));
  EXPECT_EQ(outside_before, SnapshotTree(outside));
  EXPECT_NE(std::string::npos, report.Describe().find("rolled back"));
}

TEST(CommitTransaction, CrashWhileWritingTheJournalRollsBack) {
  Fixture reference;
  // Staged files plus a half-written journal tmp file, no journal.
  EXPECT_EQ(0, RunInChild([&] {
              CommitTransaction transaction(reference.root);
              transaction.StageContents(reference.root + "/fused.ply", "new");
              WriteTextFile(reference.root + "/" + kJournalFileName + ".tmp",
                            "{\"ta");
              _exit(0);
            }));
  EXPECT_EQ(RecoveryReport::Action::kRolledBack,
            RecoverInterruptedCommit(reference.root).action);
  EXPECT_EQ(reference.old_tree, SnapshotTree(reference.root));
}

TEST(CommitTransaction, OutsideTargetsAreCommittedAndRecovered) {
  Fixture reference;
  const std::string outside = reference.dir / "outside_model";
  WriteModel(outside, true, true);
  std::string expected_images = ReadTextFile(outside + "/images.txt");
  RescaleImagesText(kScale, "images.txt", &expected_images);

  RescaleWorkspaceOptions options;
  options.extra_model_dirs = {outside};
  const size_t renames =
      ListArtefactsToRescale(reference.root, {outside}).size() + 1;
  // Crash after all but two renames: the outside model files come before the
  // depth maps in the listing, so they are new, and recovery does the rest.
  const std::string k = std::to_string(renames - 2);
  ASSERT_EQ(
      kFaultInjectExitCode,
      RunInChild(
          [&] { RescaleWorkspaceInPlace(reference.root, kScale, options); },
          k.c_str()));
  EXPECT_EQ(RecoveryReport::Action::kRolledForward,
            RecoverInterruptedCommit(reference.root).action);
  EXPECT_EQ(reference.new_tree, WithoutRecord(SnapshotTree(reference.root)));
  EXPECT_EQ(expected_images, ReadTextFile(outside + "/images.txt"));
  for (const auto& entry : SnapshotTree(outside)) {
    EXPECT_FALSE(IsTransactionFile(entry.first)) << entry.first;
  }
}

TEST(CommitTransaction, FailedStagingLeavesNothing) {
  Fixture reference;
  {
    CommitTransaction transaction(reference.root);
    transaction.StageContents(reference.root + "/fused.ply", "new");
    EXPECT_THROW(transaction.Stage(reference.root + "/sparse/images.bin",
                                   [](const std::string& staged) {
                                     WriteTextFile(staged, "half");
                                     throw InputError("writer failed");
                                   }),
                 InputError);
    EXPECT_FALSE(
        fs::exists(reference.root + "/sparse/images.bin" + kStagedSuffix));
    EXPECT_TRUE(fs::exists(reference.root + "/fused.ply" + kStagedSuffix));
  }  // destroyed without Commit
  EXPECT_EQ(reference.old_tree, SnapshotTree(reference.root));
}

TEST(CommitTransaction, RefusesToStartOverAnInterruptedCommit) {
  Fixture reference;
  ASSERT_EQ(kFaultInjectExitCode,
            RunInChild(
                [&] {
                  RescaleWorkspaceInPlace(
                      reference.root, kScale, RescaleWorkspaceOptions());
                },
                "1"));
  const Tree crashed = SnapshotTree(reference.root);
  EXPECT_THROW(CommitTransaction transaction(reference.root), InputError);
  RescaleWorkspaceOptions force;
  force.force = true;
  EXPECT_THROW(RescaleWorkspaceInPlace(reference.root, 2.0, force), InputError);
  TempDir out;
  EXPECT_THROW(WriteRescaledCopy(reference.root, out / "copy", 2.0, force),
               InputError);
  EXPECT_EQ(crashed, SnapshotTree(reference.root));
}

TEST(CommitTransaction, RecoveryOnACleanWorkspaceDoesNothing) {
  Fixture reference;
  const RecoveryReport report = RecoverInterruptedCommit(reference.root);
  EXPECT_EQ(RecoveryReport::Action::kNothing, report.action);
  EXPECT_TRUE(report.removed.empty());
  EXPECT_EQ(reference.old_tree, SnapshotTree(reference.root));
  EXPECT_THROW(RecoverInterruptedCommit(reference.dir / "missing"), InputError);
}

// ---- the record -----------------------------------------------------------

TEST(ScaleRecord, RefusesASecondScaleUnlessForcedAndComposes) {
  Fixture reference;
  const std::string root = reference.root;
  EXPECT_FALSE(ReadScaleRecord(root).IsRescaled());
  EXPECT_EQ(1.0, ReadScaleRecord(root).CumulativeScale());

  RescaleWorkspaceOptions options;
  options.tool_version = "dp-sfm 0.1";
  options.inputs = {"/dp/left", "/dp/right"};
  RescaleWorkspaceInPlace(root, kScale, options);
  EXPECT_TRUE(ReadScaleRecord(root).IsRescaled());

  // Again without force: refused, nothing changes.
  const Tree once = SnapshotTree(root);
  try {
    RescaleWorkspaceInPlace(root, 3.0, options);
    ADD_FAILURE() << "second rescale accepted without force";
  } catch (const InputError& e) {
    EXPECT_NE(std::string::npos, std::string(e.what()).find("already"));
    EXPECT_NE(std::string::npos,
              std::string(e.what()).find(kScaleRecordFileName));
  }
  EXPECT_EQ(once, SnapshotTree(root));

  // With force the scales compose.
  options.force = true;
  options.tool_version = "dp-sfm 0.2";
  const RescaleWorkspaceResult result =
      RescaleWorkspaceInPlace(root, 3.0, options);
  EXPECT_EQ(kScale * 3.0, result.entry.cumulative_scale);
  const ScaleRecord record = ReadScaleRecord(root);
  ASSERT_EQ(2u, record.entries.size());
  EXPECT_EQ(kScale, record.entries[0].scale);
  EXPECT_EQ(kScale, record.entries[0].cumulative_scale);
  EXPECT_EQ("dp-sfm 0.1", record.entries[0].tool_version);
  EXPECT_EQ(3.0, record.entries[1].scale);
  EXPECT_EQ(kScale * 3.0, record.entries[1].cumulative_scale);
  EXPECT_EQ(kScale * 3.0, record.CumulativeScale());
  EXPECT_EQ("dp-sfm 0.2", record.entries[1].tool_version);
  EXPECT_EQ((std::vector<std::string>{"/dp/left", "/dp/right"}),
            record.entries[1].inputs);

  // The files now hold the original times both scales.
  const Tree twice = SnapshotTree(root);
  std::string depth =
      reference.old_tree.at("stereo/depth_maps/image0.geometric.bin");
  RescaleDepthMap(kScale, "d", &depth);
  RescaleDepthMap(3.0, "d", &depth);
  EXPECT_EQ(depth, twice.at("stereo/depth_maps/image0.geometric.bin"));
}

TEST(ScaleRecord, JsonRoundTripAndCorruptRecord) {
  ScaleRecord record;
  record.Append(0.1, {"a"}, "v1");
  record.Append(3.0, {}, "v2");
  const ScaleRecord back = ScaleRecord::FromJson(record.ToJson(), "r.json");
  ASSERT_EQ(2u, back.entries.size());
  EXPECT_EQ(0.1, back.entries[0].scale);
  EXPECT_EQ(0.1 * 3.0, back.entries[1].cumulative_scale);
  EXPECT_EQ(record.entries[1].time, back.entries[1].time);
  EXPECT_EQ(std::vector<std::string>{"a"}, back.entries[0].inputs);

  TempDir dir;
  WriteTextFile(dir / kScaleRecordFileName, "{\"entries\": [ {\"scale\": ");
  try {
    ReadScaleRecord(dir.path());
    ADD_FAILURE() << "corrupt record accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string::npos,
              std::string(e.what()).find(kScaleRecordFileName));
  }
  WriteTextFile(dir / kScaleRecordFileName,
                "{\"entries\": [{\"scale\": -1, \"cumulative_scale\": 1}]}");
  EXPECT_THROW(ReadScaleRecord(dir.path()), InputError);
  // A corrupt record blocks a rescale (we cannot tell what was applied).
  const Tree before = SnapshotTree(dir.path());
  EXPECT_THROW(
      RescaleWorkspaceInPlace(dir.path(), 2.0, RescaleWorkspaceOptions()),
      InputError);
  EXPECT_EQ(before, SnapshotTree(dir.path()));
}

// ---- --output_path --------------------------------------------------------

TEST(WriteRescaledCopy, CopyIsRescaledAndInputUntouched) {
  Fixture reference;
  const std::string output = reference.dir / "out/rescaled";
  RescaleWorkspaceOptions options;
  options.tool_version = "dp-sfm test";
  const RescaleWorkspaceResult result =
      WriteRescaledCopy(reference.root, output, kScale, options);
  EXPECT_EQ(reference.old_tree, SnapshotTree(reference.root));
  EXPECT_EQ(reference.new_tree, WithoutRecord(SnapshotTree(output)));
  EXPECT_EQ(reference.num_renames - 1, result.rescaled_files.size());
  EXPECT_EQ(kScale, ReadScaleRecord(output).CumulativeScale());
  EXPECT_FALSE(ReadScaleRecord(reference.root).IsRescaled());
  EXPECT_FALSE(fs::exists(output + ".dpsfm-staging"));

  // Copying a rescaled workspace needs force, then composes.
  const std::string second = reference.dir / "second";
  EXPECT_THROW(WriteRescaledCopy(output, second, 2.0, options), InputError);
  EXPECT_FALSE(fs::exists(second));
  options.force = true;
  WriteRescaledCopy(output, second, 2.0, options);
  EXPECT_EQ(kScale * 2.0, ReadScaleRecord(second).CumulativeScale());
  ASSERT_EQ(2u, ReadScaleRecord(second).entries.size());
}

TEST(WriteRescaledCopy, RefusesNonEmptyTargetsAndAcceptsEmptyOnes) {
  Fixture reference;
  const std::string busy = reference.dir / "busy";
  WriteTextFile(busy + "/keep.txt", "mine");
  const Tree busy_before = SnapshotTree(busy);
  EXPECT_THROW(WriteRescaledCopy(
                   reference.root, busy, kScale, RescaleWorkspaceOptions()),
               InputError);
  EXPECT_EQ(busy_before, SnapshotTree(busy));
  WriteTextFile(reference.dir / "file", "x");
  EXPECT_THROW(WriteRescaledCopy(reference.root,
                                 reference.dir / "file",
                                 kScale,
                                 RescaleWorkspaceOptions()),
               InputError);
  // Inside the input: refused.
  EXPECT_THROW(WriteRescaledCopy(reference.root,
                                 reference.root + "/copy",
                                 kScale,
                                 RescaleWorkspaceOptions()),
               InputError);
  EXPECT_EQ(reference.old_tree, SnapshotTree(reference.root));

  const std::string empty = reference.dir / "empty";
  fs::create_directories(empty);
  WriteRescaledCopy(
      reference.root, empty + "/", kScale, RescaleWorkspaceOptions());
  EXPECT_EQ(reference.new_tree, WithoutRecord(SnapshotTree(empty)));
}

TEST(WriteRescaledCopy, FailureOrStaleStagingNeverLeavesAHalfCopy) {
  Fixture reference;
  const std::string output = reference.dir / "out";
  // A stale staging folder of an interrupted earlier copy is replaced.
  WriteTextFile(output + ".dpsfm-staging/junk", "half copy");
  WriteRescaledCopy(reference.root, output, kScale, RescaleWorkspaceOptions());
  EXPECT_EQ(reference.new_tree, WithoutRecord(SnapshotTree(output)));
  EXPECT_FALSE(fs::exists(output + ".dpsfm-staging"));

  // A corrupt artefact: no output, no staging folder, input unchanged.
  const std::string depth =
      reference.root + "/stereo/depth_maps/image2.photometric.bin";
  WriteTextFile(depth, ReadTextFile(depth).substr(0, 10));
  const Tree before = SnapshotTree(reference.root);
  const std::string output2 = reference.dir / "out2";
  try {
    WriteRescaledCopy(
        reference.root, output2, kScale, RescaleWorkspaceOptions());
    ADD_FAILURE() << "corrupt depth map accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string::npos, std::string(e.what()).find(depth));
  }
  EXPECT_FALSE(fs::exists(output2));
  EXPECT_FALSE(fs::exists(output2 + ".dpsfm-staging"));
  EXPECT_EQ(before, SnapshotTree(reference.root));
}

}  // namespace
}  // namespace dpsfm
