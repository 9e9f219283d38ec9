#include "dpsfm/colmap/rescale/transaction.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <map>
#include <set>
#include <sstream>
#include <stdexcept>

#include <nlohmann/json.hpp>

#include "colmap/util/logging.h"
#include "dpsfm/colmap/rescale/rescale.h"
#include "dpsfm/colmap/util/durable_file.h"
#include "dpsfm/colmap/util/input_error.h"
#include "dpsfm/colmap/util/paths.h"

namespace dpsfm {

const char kStagedSuffix[] = ".dpsfm-staged";
const char kJournalFileName[] = "dp_scale_journal.json";
const char kStagingListFileName[] = "dp_scale_staging.json";
const char kScaleRecordFileName[] = "dp_scale_record.json";
const char kFaultInjectCommitEnv[] = "DPSFM_FAULT_INJECT_COMMIT_AFTER";

namespace {

namespace fs = std::filesystem;
using nlohmann::json;

// Absolute path with resolved symlinks in its folder part; the file itself
// need not exist, its folder must.
fs::path ResolveTarget(const std::string& target) {
  const fs::path path = fs::absolute(target);
  const fs::path parent = path.parent_path();
  if (!fs::is_directory(parent)) {
    throw InputError("folder of " + target + " does not exist");
  }
  return fs::canonical(parent) / path.filename();
}

// Journal and staging list paths are stored relative to the root when
// inside it, so a workspace moved between crash and recovery still works.
std::string StorePath(const fs::path& path, const fs::path& root) {
  if (IsWithin(path, root)) return path.lexically_relative(root).string();
  return path.string();
}

fs::path LoadPath(const std::string& stored, const fs::path& root) {
  const fs::path path(stored);
  return path.is_absolute() ? path : root / path;
}

json ReadJsonFile(const fs::path& path, const char* what) {
  const std::string text = ReadFileBytes(path.string());
  try {
    return json::parse(text);
  } catch (const std::exception& e) {
    throw InputError(std::string(what) + " " + path.string() +
                     " is not valid JSON: " + e.what());
  }
}

std::vector<fs::path> ReadPathList(const fs::path& file,
                                   const char* key,
                                   const fs::path& root,
                                   const char* what) {
  const json document = ReadJsonFile(file, what);
  std::vector<fs::path> paths;
  if (!document.is_object() || !document.contains(key) ||
      !document[key].is_array()) {
    throw InputError(std::string(what) + " " + file.string() + " has no \"" +
                     key + "\" list");
  }
  for (const json& entry : document[key]) {
    if (!entry.is_string()) {
      throw InputError(std::string(what) + " " + file.string() +
                       " holds a non-string path");
    }
    paths.push_back(LoadPath(entry.get<std::string>(), root));
  }
  return paths;
}

// Reads DPSFM_FAULT_INJECT_COMMIT_AFTER; -1 when unset or not a number.
long FaultInjectionPoint() {
  const char* value = std::getenv(kFaultInjectCommitEnv);
  if (value == nullptr || *value == '\0') return -1;
  char* end = nullptr;
  const long n = std::strtol(value, &end, 10);
  return (*end == '\0' && n >= 0) ? n : -1;
}

void MaybeInjectFault(long fault_point, long renames_done) {
  if (fault_point == renames_done) {
    std::_Exit(kFaultInjectExitCode);
  }
}

void SyncFolders(const std::set<std::string>& dirs) {
  for (const std::string& dir : dirs) SyncToDisk(dir);
}

// Deletes staged files under the root (recursively) and in `outside_dirs`,
// plus the tmp files of journal and staging list.
void SweepStagedFiles(const fs::path& root,
                      const std::vector<fs::path>& outside_dirs,
                      std::vector<std::string>* removed) {
  std::vector<fs::path> doomed;
  std::error_code ec;
  for (fs::recursive_directory_iterator it(root, ec), end; !ec && it != end;
       it.increment(ec)) {
    if (EndsWith(it->path().filename().string(), kStagedSuffix) &&
        !fs::is_directory(fs::symlink_status(it->path()))) {
      doomed.push_back(it->path());
    }
  }
  for (const fs::path& dir : outside_dirs) {
    if (!fs::is_directory(dir)) continue;
    for (fs::directory_iterator it(dir, ec), end; !ec && it != end;
         it.increment(ec)) {
      if (EndsWith(it->path().filename().string(), kStagedSuffix) &&
          !fs::is_directory(fs::symlink_status(it->path()))) {
        doomed.push_back(it->path());
      }
    }
  }
  doomed.push_back(root / (std::string(kJournalFileName) + kAtomicWriteSuffix));
  doomed.push_back(root /
                   (std::string(kStagingListFileName) + kAtomicWriteSuffix));
  std::sort(doomed.begin(), doomed.end());
  doomed.erase(std::unique(doomed.begin(), doomed.end()), doomed.end());
  for (const fs::path& path : doomed) {
    if (!PathExists(path)) continue;
    RemoveOrThrow(path);
    removed->push_back(path.string());
  }
}

void RefuseIfJournal(const fs::path& root) {
  if (PathExists(root / kJournalFileName)) {
    throw InputError("workspace " + root.string() +
                     " holds an interrupted rescale (" +
                     (root / kJournalFileName).string() +
                     "); it must be recovered before anything else");
  }
}

}  // namespace

// ---- record ------------------------------------------------------------

double ScaleRecord::CumulativeScale() const {
  return entries.empty() ? 1.0 : entries.back().cumulative_scale;
}

const ScaleRecordEntry& ScaleRecord::Append(
    double scale,
    const std::vector<std::string>& inputs,
    const std::string& tool_version) {
  CheckScale(scale);
  ScaleRecordEntry entry;
  entry.scale = scale;
  entry.cumulative_scale = CumulativeScale() * scale;
  entry.time = CurrentTimeIso8601Utc();
  entry.inputs = inputs;
  entry.tool_version = tool_version;
  entries.push_back(entry);
  return entries.back();
}

std::string ScaleRecord::ToJson() const {
  json document;
  document["format"] = "dp-sfm scale record";
  document["version"] = 1;
  document["entries"] = json::array();
  for (const ScaleRecordEntry& entry : entries) {
    document["entries"].push_back({{"scale", entry.scale},
                                   {"cumulative_scale", entry.cumulative_scale},
                                   {"time", entry.time},
                                   {"inputs", entry.inputs},
                                   {"tool_version", entry.tool_version}});
  }
  return document.dump(2) + "\n";
}

ScaleRecord ScaleRecord::FromJson(const std::string& text,
                                  const std::string& path) {
  json document;
  try {
    document = json::parse(text);
  } catch (const std::exception& e) {
    throw InputError("scale record " + path +
                     " is not valid JSON: " + e.what());
  }
  const auto bad = [&path](const std::string& what) {
    return InputError("scale record " + path + " is invalid: " + what);
  };
  if (!document.is_object() || !document.contains("entries") ||
      !document["entries"].is_array()) {
    throw bad("no \"entries\" list");
  }
  ScaleRecord record;
  for (const json& item : document["entries"]) {
    ScaleRecordEntry entry;
    if (!item.is_object() || !item.contains("scale") ||
        !item["scale"].is_number() || !item.contains("cumulative_scale") ||
        !item["cumulative_scale"].is_number()) {
      throw bad("an entry has no numeric \"scale\" and \"cumulative_scale\"");
    }
    entry.scale = item["scale"].get<double>();
    entry.cumulative_scale = item["cumulative_scale"].get<double>();
    if (!(std::isfinite(entry.scale) && entry.scale > 0 &&
          std::isfinite(entry.cumulative_scale) &&
          entry.cumulative_scale > 0)) {
      throw bad("an entry has a scale that is not a positive number");
    }
    if (item.contains("time") && item["time"].is_string()) {
      entry.time = item["time"].get<std::string>();
    }
    if (item.contains("tool_version") && item["tool_version"].is_string()) {
      entry.tool_version = item["tool_version"].get<std::string>();
    }
    if (item.contains("inputs") && item["inputs"].is_array()) {
      for (const json& input : item["inputs"]) {
        if (input.is_string()) entry.inputs.push_back(input.get<std::string>());
      }
    }
    record.entries.push_back(entry);
  }
  return record;
}

std::string ScaleRecordPath(const std::string& workspace_root) {
  return (fs::path(workspace_root) / kScaleRecordFileName).string();
}

ScaleRecord ReadScaleRecord(const std::string& workspace_root) {
  const std::string path = ScaleRecordPath(workspace_root);
  if (!PathExists(path)) return ScaleRecord();
  return ScaleRecord::FromJson(ReadFileBytes(path), path);
}

std::string CurrentTimeIso8601Utc() {
  const std::time_t now = std::time(nullptr);
  std::tm utc;
  gmtime_r(&now, &utc);
  char buffer[32];
  std::strftime(buffer, sizeof(buffer), "%Y-%m-%dT%H:%M:%SZ", &utc);
  return buffer;
}

// ---- transaction ---------------------------------------------------------

CommitTransaction::CommitTransaction(const std::string& workspace_root) {
  if (!fs::is_directory(workspace_root)) {
    throw InputError("workspace is not a directory: " + workspace_root);
  }
  root_ = fs::canonical(workspace_root).string();
  RefuseIfJournal(root_);
}

CommitTransaction::~CommitTransaction() {
  // A destructor must not throw. Leftover staged files are harmless (the
  // next run's recovery deletes them), but they are said, not swallowed.
  try {
    Abort();
  } catch (const std::exception& error) {
    LOG(WARNING) << "could not remove the staged files of an abandoned "
                    "rescale (the next run deletes them): "
                 << error.what();
  }
}

void CommitTransaction::RegisterOutsideDir(const std::string& dir) {
  if (std::find(outside_dirs_.begin(), outside_dirs_.end(), dir) !=
      outside_dirs_.end()) {
    return;
  }
  outside_dirs_.push_back(dir);
  // Recorded before anything is staged there, so a rollback after a crash
  // knows where to look.
  json document;
  document["version"] = 1;
  document["dirs"] = outside_dirs_;
  WriteFileAtomically(fs::path(root_) / kStagingListFileName,
                      document.dump(2) + "\n");
}

void CommitTransaction::Stage(
    const std::string& target_path,
    const std::function<void(const std::string&)>& write_staged) {
  if (committed_ || PathExists(fs::path(root_) / kJournalFileName)) {
    throw std::logic_error("CommitTransaction::Stage after Commit");
  }
  const fs::path target = ResolveTarget(target_path);
  if (fs::is_directory(target)) {
    throw InputError("cannot replace folder " + target.string() +
                     " with a file");
  }
  if (!IsWithin(target, root_)) {
    RegisterOutsideDir(target.parent_path().string());
  }
  const std::string staged = target.string() + kStagedSuffix;
  try {
    write_staged(staged);
    SyncToDisk(staged);
  } catch (...) {
    std::error_code ec;
    fs::remove(staged, ec);
    throw;
  }
  if (std::find(targets_.begin(), targets_.end(), target.string()) ==
      targets_.end()) {
    targets_.push_back(target.string());
  }
}

void CommitTransaction::StageContents(const std::string& target_path,
                                      const std::string& contents,
                                      int mode) {
  const unsigned int bits =
      mode >= 0 ? static_cast<unsigned int>(mode)
                : (PathExists(target_path) ? FileMode(target_path) : 0644u);
  Stage(target_path, [&](const std::string& staged) {
    WriteFileDurably(staged, contents, bits);
  });
}

void CommitTransaction::Commit() {
  if (committed_) throw std::logic_error("CommitTransaction committed twice");
  const fs::path root(root_);
  const std::string record = ScaleRecordPath(root_);

  // The record goes last: a workspace whose record says "rescaled" has all
  // its files rescaled, even to a reader that ignores the journal.
  std::vector<std::string> order = targets_;
  std::stable_partition(order.begin(), order.end(), [&](const std::string& t) {
    return t != record;
  });

  std::set<std::string> dirs;
  for (const std::string& target : order) {
    dirs.insert(fs::path(target).parent_path().string());
  }
  // Staged names must be durable before the journal points at them.
  SyncFolders(dirs);

  json journal;
  journal["version"] = 1;
  journal["targets"] = json::array();
  for (const std::string& target : order) {
    journal["targets"].push_back(StorePath(target, root));
  }
  WriteFileAtomically(root / kJournalFileName, journal.dump(2) + "\n");
  // From here on the commit is decided: a failure leaves the journal, and
  // recovery rolls forward; Abort() must not delete staged files any more.

  const long fault_point = FaultInjectionPoint();
  MaybeInjectFault(fault_point, 0);
  long renames = 0;
  for (const std::string& target : order) {
    RenameOrThrow(target + kStagedSuffix, target);
    MaybeInjectFault(fault_point, ++renames);
  }
  SyncFolders(dirs);

  RemoveOrThrow(root / kJournalFileName);
  RemoveOrThrow(root / kStagingListFileName);
  SyncToDisk(root_);
  committed_ = true;
}

void CommitTransaction::Abort() {
  if (committed_ || PathExists(fs::path(root_) / kJournalFileName)) return;
  for (const std::string& target : targets_) {
    RemoveOrThrow(target + kStagedSuffix);
  }
  targets_.clear();
  if (!outside_dirs_.empty()) {
    RemoveOrThrow(fs::path(root_) / kStagingListFileName);
    outside_dirs_.clear();
  }
}

// ---- the journal ----------------------------------------------------------

std::string JournalPath(const std::string& workspace_root) {
  const fs::path journal = fs::path(workspace_root) / kJournalFileName;
  return PathExists(journal) ? journal.string() : std::string();
}

std::vector<std::string> ReadJournalTargets(const std::string& workspace_root) {
  const std::string journal = JournalPath(workspace_root);
  if (journal.empty()) return {};
  const fs::path root = fs::canonical(workspace_root);
  std::vector<std::string> targets;
  for (const fs::path& target :
       ReadPathList(journal, "targets", root, "rescale journal")) {
    targets.push_back(target.string());
  }
  return targets;
}

std::string StagedPath(const std::string& target) {
  return target + kStagedSuffix;
}

// ---- recovery ------------------------------------------------------------

std::string RecoveryReport::Describe() const {
  std::ostringstream text;
  switch (action) {
    case Action::kNothing:
      text << "no interrupted rescale found";
      break;
    case Action::kRolledForward:
      text << "finished an interrupted rescale (" << completed.size()
           << " file(s) moved into place)";
      break;
    case Action::kRolledBack:
      text << "rolled back an unfinished rescale (" << removed.size()
           << " staged file(s) deleted; the workspace was not changed)";
      break;
  }
  return text.str();
}

RecoveryReport RecoverInterruptedCommit(const std::string& workspace_root) {
  if (!fs::is_directory(workspace_root)) {
    throw InputError("workspace is not a directory: " + workspace_root);
  }
  const fs::path root = fs::canonical(workspace_root);
  const fs::path journal = root / kJournalFileName;
  const fs::path staging_list = root / kStagingListFileName;
  RecoveryReport report;

  std::vector<fs::path> outside_dirs;
  if (PathExists(staging_list)) {
    outside_dirs = ReadPathList(staging_list, "dirs", root, "staging list");
  }

  if (PathExists(journal)) {
    const std::vector<fs::path> targets =
        ReadPathList(journal, "targets", root, "rescale journal");
    std::set<std::string> dirs;
    for (const fs::path& target : targets) {
      const fs::path staged = target.string() + kStagedSuffix;
      if (PathExists(staged)) {
        RenameOrThrow(staged, target);
        report.completed.push_back(target.string());
      } else if (!PathExists(target)) {
        throw std::runtime_error("cannot finish the interrupted rescale of " +
                                 root.string() + ": neither " +
                                 target.string() + " nor its staged version " +
                                 staged.string() + " exists");
      }
      dirs.insert(target.parent_path().string());
    }
    SyncFolders(dirs);
    RemoveOrThrow(journal);
    SyncToDisk(root.string());
    report.action = RecoveryReport::Action::kRolledForward;
  }

  SweepStagedFiles(root, outside_dirs, &report.removed);
  if (PathExists(staging_list)) {
    RemoveOrThrow(staging_list);
    report.removed.push_back(staging_list.string());
  }
  if (report.action == RecoveryReport::Action::kNothing &&
      !report.removed.empty()) {
    report.action = RecoveryReport::Action::kRolledBack;
  }
  if (!report.removed.empty()) SyncToDisk(root.string());
  return report;
}

}  // namespace dpsfm
