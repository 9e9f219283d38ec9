#include "dpsfm/colmap/rescale/rescale_plan.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <stdexcept>

#include "dpsfm/colmap/rescale/model_check.h"
#include "dpsfm/colmap/util/durable_file.h"
#include "dpsfm/colmap/util/input_error.h"
#include "dpsfm/colmap/util/paths.h"

namespace dpsfm {
namespace {

namespace fs = std::filesystem;

const char kCopyStagingSuffix[] = ".dpsfm-staging";

// The key of a file in `recovered_content`: absolute, folders resolved.
std::string CanonicalKey(const std::string& path) {
  return fs::weakly_canonical(fs::absolute(path)).string();
}

std::string FormatScale(double value) {
  char buffer[64];
  std::snprintf(buffer, sizeof(buffer), "%.10g", value);
  return buffer;
}

// The already-rescaled note: how often, when, by how much, and where.
std::string AlreadyRescaledNote(const ScaleRecord& record,
                                const std::string& root) {
  const ScaleRecordEntry& last = record.entries.back();
  std::ostringstream note;
  note << "workspace " << root
       << " was already rescaled to metres by dp_scale_estimator ("
       << record.entries.size() << " time(s), last on " << last.time << " by "
       << FormatScale(last.scale) << ", cumulative scale "
       << FormatScale(record.CumulativeScale()) << "; see "
       << ScaleRecordPath(root) << ")";
  return note.str();
}

// Step 1: the journal of an interrupted commit. In place it was recovered
// before planning (a journal left is a caller error); a copy is refused; a
// dry run maps each target to the file recovery will leave in its place.
void PlanJournal(const RescalePlanOptions& options, RescalePlan* plan) {
  const std::string journal = JournalPath(options.workspace_root);
  if (journal.empty()) return;
  if (options.mode != RescaleMode::kDryRun) {
    throw InputError(
        "workspace " + options.workspace_root +
        " holds an interrupted rescale (" + journal + ")" +
        (options.mode == RescaleMode::kCopy
             ? "; nothing was written. Run dp_scale_estimator once in place "
               "on it (without --output_path and --dry_run) to finish that "
               "rescale, then write the copy (with --force 1: the workspace "
               "is then in metres)"
             : "; it must be recovered before anything else"));
  }
  plan->journal_path = journal;
  for (const std::string& target : ReadJournalTargets(options.workspace_root)) {
    const std::string staged = StagedPath(target);
    if (PathExists(staged)) {
      plan->recovered_content[CanonicalKey(target)] = staged;
    } else if (!PathExists(target)) {
      throw InputError("the interrupted rescale in " + journal +
                       " cannot be finished: neither " + target +
                       " nor its staged version exists (the workspace was "
                       "changed by hand since)");
    }
  }
}

// Step 2: the record, read once (its staged version in a dry run over an
// interrupted commit), and the already-rescaled rule.
void PlanRecord(const RescalePlanOptions& options, RescalePlan* plan) {
  const std::string path = ScaleRecordPath(options.workspace_root);
  const std::string read = plan->ReadPath(path);
  if (PathExists(read)) {
    plan->record = ScaleRecord::FromJson(ReadFileBytes(read), path);
  }
  if (!plan->record.IsRescaled() || options.force) return;
  const std::string note =
      AlreadyRescaledNote(plan->record, options.workspace_root);
  switch (options.mode) {
    case RescaleMode::kInPlace:
      throw InputError(note +
                       "; nothing was changed. Pass --force 1 to apply "
                       "another scale on top, or --dry_run 1 to estimate only");
    case RescaleMode::kCopy:
      throw InputError(note +
                       "; nothing was written. Pass --force 1 to write a copy "
                       "with another scale on top, or --dry_run 1 to "
                       "estimate only");
    case RescaleMode::kDryRun:
      plan->warnings.push_back(note +
                               "; a rescale would need --force 1 (the "
                               "scales then compose)");
      break;
  }
}

// A depth map's header against its size: the data are not read (they are
// the bulk of a workspace; the commit reads each once).
void CheckDepthMapStructure(const std::string& path, const std::string& read) {
  std::ifstream file(read, std::ios::binary);
  std::string head(kDepthMapHeadBytes, '\0');
  file.read(&head[0], head.size());
  head.resize(static_cast<size_t>(std::max<std::streamsize>(0, file.gcount())));
  std::error_code ec;
  const uintmax_t size = fs::file_size(read, ec);
  if (!file.good() && head.empty()) {
    throw InputError("cannot rescale " + path + ": cannot read it");
  }
  DepthMapLayout layout;
  std::string problem;
  if (ec || !ParseDepthMapHeader(head, size, &layout, &problem)) {
    throw InputError("cannot rescale " + path + ": " +
                     (ec ? ec.message() : problem));
  }
}

// One spelling per file, to know a file the model check parsed among the
// artefacts whatever path each was reached by.
std::string FileKey(const std::string& path) {
  return fs::weakly_canonical(fs::absolute(path)).string();
}

// Step 3: every artefact validated once, without the scale: a depth map's
// header against its size, a model file's structure with the one parser of
// model files unless the model check (`checked`, FileKey) parsed it
// already, a PLY's whole structure (its rescaler's own parse; model files
// and PLY are small next to the depths).
void ValidateArtefacts(const RescalePlan& plan,
                       const std::set<std::string>& checked) {
  for (const Artefact& artefact : plan.artefacts) {
    const std::string read = plan.ReadPath(artefact.path);
    if (artefact.type == ArtefactType::kDepthMap) {
      CheckDepthMapStructure(artefact.path, read);
    } else if (!IsModelFile(artefact.type)) {
      std::string bytes = ReadFileBytes(read);
      RescaleContents(artefact.type, 1.0, artefact.path, &bytes);
    } else if (checked.count(FileKey(artefact.path)) == 0) {
      CheckModelFileContents(artefact.type, artefact.path, ReadFileBytes(read));
    }
  }
}

// Step 4: the folders the commit writes must be writable.
void CheckWritable(const RescalePlan& plan) {
  std::set<std::string> dirs;
  if (plan.mode == RescaleMode::kCopy) {
    // The copy creates the folders it lacks: the nearest that exists must
    // be writable.
    fs::path parent = fs::absolute(plan.output_path).parent_path();
    while (!PathExists(parent) && parent.has_parent_path() &&
           parent.parent_path() != parent) {
      parent = parent.parent_path();
    }
    dirs.insert(parent.string());
  } else {
    dirs.insert(fs::path(plan.workspace_root).string());
    for (const Artefact& artefact : plan.artefacts) {
      dirs.insert(fs::path(artefact.path).parent_path().string());
    }
  }
  for (const std::string& dir : dirs) {
    std::string why;
    if (CanCreateIn(dir, &why)) continue;
    if (plan.mode == RescaleMode::kCopy) {
      throw InputError("cannot write the rescaled copy: " + dir +
                       " is not writable (" + why +
                       "); nothing was changed. Choose an --output_path in a "
                       "writable folder");
    }
    throw InputError("cannot rescale in place: " + dir + " is not writable (" +
                     why +
                     "); nothing was changed. Make it writable, write a "
                     "rescaled copy with --output_path DIR, or estimate only "
                     "with --dry_run 1");
  }
}

// A copy's target: absent or an empty folder, outside the input; the extra
// models inside the input (the copy holds only the input's files).
void CheckCopyTarget(const RescalePlanOptions& options, RescalePlan* plan) {
  const fs::path input = fs::canonical(options.workspace_root);
  fs::path output = fs::absolute(options.output_path).lexically_normal();
  if (output.filename() == "." || output.filename().empty()) {
    output = output.parent_path();
  }
  const fs::path resolved = fs::weakly_canonical(output);
  if (resolved == input) {
    throw InputError(
        "--output_path is the input itself; leave it out to rescale in "
        "place: " +
        options.output_path);
  }
  if (PathExists(output) &&
      (!fs::is_directory(output) || !fs::is_empty(output))) {
    throw InputError("output folder " + options.output_path +
                     " already exists and is not empty");
  }
  if (IsWithin(resolved, input)) {
    throw InputError("output folder " + options.output_path +
                     " lies inside the input workspace " +
                     options.workspace_root);
  }
  plan->output_path = output.string();
  plan->extra_model_dirs.clear();
  for (const std::string& dir : options.extra_model_dirs) {
    if (!fs::is_directory(dir) || !IsWithin(fs::canonical(dir), input)) {
      throw InputError("model folder " + dir + " is not inside the workspace " +
                       options.workspace_root +
                       ", so it cannot be part of the rescaled copy");
    }
    plan->extra_model_dirs.push_back(fs::canonical(dir).string());
  }
}

// What a rescale would write and whether it could: the listing (which
// refuses files of unknown treatment), each artefact's structure, the
// folders' permissions.
void PlanArtefacts(const RescalePlanOptions& options,
                   const std::set<std::string>& checked,
                   RescalePlan* plan) {
  if (options.mode == RescaleMode::kCopy) CheckCopyTarget(options, plan);
  const std::string root = options.mode == RescaleMode::kCopy
                               ? fs::canonical(options.workspace_root).string()
                               : options.workspace_root;
  plan->artefacts = ListArtefactsToRescale(root, plan->extra_model_dirs);
  ValidateArtefacts(*plan, checked);
  CheckWritable(*plan);
}

void StampPlannedFiles(RescalePlan* plan) {
  for (const Artefact& artefact : plan->artefacts) {
    plan->stamps.push_back(StampFile(artefact.path));
  }
  plan->stamps.push_back(StampFile(ScaleRecordPath(plan->workspace_root)));
  plan->stamps.push_back(
      StampFile((fs::path(plan->workspace_root) / kJournalFileName).string()));
}

// The commit's first step: nothing planned changed since.
void RefuseIfChanged(const RescalePlan& plan) {
  for (const FileStamp& planned : plan.stamps) {
    const FileStamp now = StampFile(planned.path);
    if (now.exists == planned.exists && now.size == planned.size &&
        now.mtime_ns == planned.mtime_ns) {
      continue;
    }
    std::ostringstream what;
    if (!planned.exists) {
      what << "appeared";
    } else if (!now.exists) {
      what << "disappeared";
    } else {
      what << "changed (" << planned.size << " -> " << now.size
           << " bytes, or its modification time)";
    }
    throw InputError(planned.path + " " + what.str() +
                     " while the scale was estimated; nothing was written. "
                     "Run again once nothing else writes to the workspace");
  }
}

RescaleWorkspaceResult CommitInPlace(const RescalePlan& plan,
                                     double scale,
                                     const RescaleProvenance& provenance) {
  CommitTransaction transaction(plan.workspace_root);
  RescaleWorkspaceResult result;
  for (const Artefact& artefact : plan.artefacts) {
    transaction.Stage(artefact.path, [&](const std::string& staged) {
      WriteRescaledArtefact(artefact, scale, staged);
    });
    result.rescaled_files.push_back(artefact.path);
  }
  ScaleRecord record = plan.record;
  result.entry =
      record.Append(scale, provenance.inputs, provenance.tool_version);
  result.record_path = ScaleRecordPath(plan.workspace_root);
  transaction.StageContents(result.record_path, record.ToJson(), 0644);
  transaction.Commit();
  return result;
}

// Transaction leftovers of the input are not part of a copy; its record is
// written anew.
bool IsTransactionFile(const std::string& name, const std::string& relative) {
  return EndsWith(name, kStagedSuffix) || relative == kScaleRecordFileName ||
         relative == kStagingListFileName ||
         relative == std::string(kJournalFileName) + kAtomicWriteSuffix ||
         relative == std::string(kStagingListFileName) + kAtomicWriteSuffix;
}

RescaleWorkspaceResult WriteCopy(const RescalePlan& plan,
                                 double scale,
                                 const RescaleProvenance& provenance) {
  const fs::path input = fs::canonical(plan.workspace_root);
  const fs::path output(plan.output_path);
  // Artefacts by their path relative to the input.
  std::map<std::string, ArtefactType> artefacts;
  for (const Artefact& artefact : plan.artefacts) {
    artefacts[fs::path(artefact.path).lexically_relative(input).string()] =
        artefact.type;
  }
  const fs::path staging = output.string() + kCopyStagingSuffix;
  std::error_code ec;
  fs::remove_all(staging, ec);  // a stale half copy of an interrupted run
  if (ec) {
    throw std::runtime_error("cannot remove the stale staging folder " +
                             staging.string() + ": " + ec.message());
  }
  fs::create_directories(output.parent_path());
  RescaleWorkspaceResult result;
  try {
    fs::create_directory(staging);
    std::vector<std::string> dirs = {staging.string()};
    for (fs::recursive_directory_iterator it(input), end; it != end; ++it) {
      const fs::path& from = it->path();
      const std::string relative = from.lexically_relative(input).string();
      const fs::path to = staging / relative;
      const fs::file_status status = fs::symlink_status(from);
      if (fs::is_symlink(status)) {
        fs::copy_symlink(from, to);
      } else if (fs::is_directory(status)) {
        fs::create_directory(to);
        dirs.push_back(to.string());
      } else if (fs::is_regular_file(status)) {
        if (IsTransactionFile(from.filename().string(), relative)) continue;
        const auto artefact = artefacts.find(relative);
        if (artefact != artefacts.end()) {
          WriteRescaledArtefact(
              {artefact->second, from.string()}, scale, to.string());
          result.rescaled_files.push_back((output / relative).string());
        } else {
          CopyFileDurably(from, to);
        }
      }
      // Sockets, fifos and devices are not workspace data; skipped.
    }
    ScaleRecord record = plan.record;
    result.entry =
        record.Append(scale, provenance.inputs, provenance.tool_version);
    WriteFileDurably((staging / kScaleRecordFileName).string(),
                     record.ToJson());
    for (const std::string& dir : dirs) SyncToDisk(dir);
    // rename(2) replaces an empty folder, so an existing empty output is
    // fine; the copy appears at `output` in one step.
    RenameOrThrow(staging, output);
    SyncToDisk(output.parent_path().string());
  } catch (...) {
    fs::remove_all(staging, ec);
    throw;
  }
  result.record_path = (output / kScaleRecordFileName).string();
  return result;
}

RescalePlanOptions OneCallOptions(RescaleMode mode,
                                  const std::string& workspace_root,
                                  const std::string& output_path,
                                  const RescaleWorkspaceOptions& options) {
  RescalePlanOptions plan;
  plan.mode = mode;
  plan.workspace_root = workspace_root;
  plan.output_path = output_path;
  plan.extra_model_dirs = options.extra_model_dirs;
  plan.force = options.force;
  return plan;
}

}  // namespace

FileStamp StampFile(const std::string& path) {
  FileStamp stamp;
  stamp.path = path;
  std::error_code ec;
  const fs::file_status status = fs::status(path, ec);
  if (ec || !fs::exists(status)) return stamp;
  stamp.exists = true;
  if (fs::is_regular_file(status)) stamp.size = fs::file_size(path, ec);
  const fs::file_time_type time = fs::last_write_time(path, ec);
  if (!ec) {
    stamp.mtime_ns = std::chrono::duration_cast<std::chrono::nanoseconds>(
                         time.time_since_epoch())
                         .count();
  }
  return stamp;
}

std::string RescalePlan::ReadPath(const std::string& path) const {
  if (recovered_content.empty()) return path;
  const auto found = recovered_content.find(CanonicalKey(path));
  return found == recovered_content.end() ? path : found->second;
}

std::vector<std::string> RescalePlan::StagedFilesRead() const {
  std::vector<std::string> staged;
  for (const auto& entry : recovered_content) staged.push_back(entry.second);
  return staged;
}

std::string RescalePlan::Summary() const {
  int model = 0, depth = 0, ply = 0;
  for (const Artefact& artefact : artefacts) {
    model += artefact.type != ArtefactType::kDepthMap &&
             artefact.type != ArtefactType::kPly;
    depth += artefact.type == ArtefactType::kDepthMap;
    ply += artefact.type == ArtefactType::kPly;
  }
  std::ostringstream text;
  text << artefacts.size() << " files (" << model << " model files, " << depth
       << " depth maps, " << ply << " PLY) and the scale record";
  return text.str();
}

RescalePlan PlanRescale(const RescalePlanOptions& options) {
  if (!fs::is_directory(options.workspace_root)) {
    throw InputError("workspace is not a directory: " + options.workspace_root);
  }
  RescalePlan plan;
  plan.mode = options.mode;
  plan.workspace_root = options.workspace_root;
  plan.extra_model_dirs = options.extra_model_dirs;
  plan.force = options.force;
  PlanJournal(options, &plan);
  if (plan.interrupted()) {
    plan.warnings.push_back(
        "workspace " + options.workspace_root +
        " holds an interrupted rescale (" + plan.journal_path +
        "): this dry run reads the " +
        std::to_string(plan.recovered_content.size()) +
        " staged files it lists in place of their targets, as recovery will "
        "leave them, and writes nothing. Run once in place (without "
        "--dry_run and --output_path) to finish that rescale");
  }
  PlanRecord(options, &plan);
  // The files the model check parsed are not parsed again below.
  std::set<std::string> checked;
  if (!options.estimate_model_dir.empty()) {
    for (const std::string& path : CheckModel(options.estimate_model_dir,
                                              [&plan](const std::string& path) {
                                                return plan.ReadPath(path);
                                              })) {
      checked.insert(FileKey(path));
    }
  }
  if (options.mode != RescaleMode::kDryRun) {
    PlanArtefacts(options, checked, &plan);
    StampPlannedFiles(&plan);
    return plan;
  }
  // A dry run plans the rescale in place it stands for and says what would
  // stop it, without stopping.
  RescalePlanOptions in_place = options;
  in_place.mode = RescaleMode::kInPlace;
  try {
    PlanArtefacts(in_place, checked, &plan);
  } catch (const InputError& error) {
    plan.refusal = error.what();
  }
  return plan;
}

RescaleWorkspaceResult ExecuteRescalePlan(const RescalePlan& plan,
                                          double scale,
                                          const RescaleProvenance& provenance) {
  CheckScale(scale);
  if (plan.mode == RescaleMode::kDryRun) {
    throw std::logic_error("ExecuteRescalePlan on a dry run's plan");
  }
  RefuseIfChanged(plan);
  return plan.mode == RescaleMode::kInPlace
             ? CommitInPlace(plan, scale, provenance)
             : WriteCopy(plan, scale, provenance);
}

RescaleWorkspaceResult RescaleWorkspaceInPlace(
    const std::string& workspace_root,
    double scale,
    const RescaleWorkspaceOptions& options) {
  CheckScale(scale);
  const RescalePlan plan = PlanRescale(
      OneCallOptions(RescaleMode::kInPlace, workspace_root, "", options));
  return ExecuteRescalePlan(
      plan, scale, {options.inputs, options.tool_version});
}

RescaleWorkspaceResult WriteRescaledCopy(
    const std::string& workspace_root,
    const std::string& output_path,
    double scale,
    const RescaleWorkspaceOptions& options) {
  CheckScale(scale);
  const RescalePlan plan = PlanRescale(
      OneCallOptions(RescaleMode::kCopy, workspace_root, output_path, options));
  return ExecuteRescalePlan(
      plan, scale, {options.inputs, options.tool_version});
}

}  // namespace dpsfm
