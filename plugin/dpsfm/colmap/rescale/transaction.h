// Applying a scale to a whole workspace all-or-nothing, recovering from a
// crash in the middle, and the workspace's record of applied scales.
//
// Protocol (CommitTransaction):
//  1. Stage: each new file is written next to its target as
//     `<target>.dpsfm-staged` and fsync'd. Originals are untouched; an error
//     or crash here leaves only staged files, which recovery deletes.
//  2. Journal: `<root>/dp_scale_journal.json` (tmp + fsync + rename) lists
//     every target. From the moment it exists the commit is decided.
//  3. Renames: each staged file is renamed over its target (atomic per
//     file), the scale record last; then the directories are fsync'd.
//  4. The journal is removed.
// A kill at any moment leaves every file fully old or fully new, and
// RecoverInterruptedCommit() finishes the renames (journal present) or
// deletes the staged files (no journal).
//
// Targets outside the root (extra model folders) are listed in
// `<root>/dp_scale_staging.json` while staged, so a rollback finds them too.
#pragma once

#include <functional>
#include <string>
#include <vector>

namespace dpsfm {

// Suffix of a staged file, next to its target.
extern const char kStagedSuffix[];  // ".dpsfm-staged"
// In the workspace root.
extern const char kJournalFileName[];      // "dp_scale_journal.json"
extern const char kStagingListFileName[];  // "dp_scale_staging.json"
extern const char kScaleRecordFileName[];  // "dp_scale_record.json"
// TEST ONLY: if this environment variable is N >= 0, Commit() calls
// std::_Exit(77) right after its N-th rename (N = 0: right after the journal
// is in place, before any rename), to simulate a crash mid-commit. Never set
// it in production.
// "DPSFM_FAULT_INJECT_COMMIT_AFTER"
extern const char kFaultInjectCommitEnv[];
constexpr int kFaultInjectExitCode = 77;

// ---- the record of applied scales -----------------------------------------

struct ScaleRecordEntry {
  // The factor applied by this run (metric = scale * previous units).
  double scale = 1.0;
  // Product of every scale applied so far, this one included: the files now
  // hold cumulative_scale * (original model units).
  double cumulative_scale = 1.0;
  // ISO 8601 UTC, e.g. "2024-05-01T12:34:56Z".
  std::string time;
  // What the scale was estimated from (paths), as given by the caller.
  std::vector<std::string> inputs;
  // Tool version string, as given by the caller.
  std::string tool_version;
};

struct ScaleRecord {
  std::vector<ScaleRecordEntry> entries;

  // True once any scale was applied: the workspace is in metres.
  bool IsRescaled() const { return !entries.empty(); }
  // 1 for a workspace never rescaled.
  double CumulativeScale() const;
  // Appends an entry for `scale` with cumulative = CumulativeScale() * scale
  // and the current time; returns it.
  const ScaleRecordEntry& Append(double scale,
                                 const std::vector<std::string>& inputs,
                                 const std::string& tool_version);
  std::string ToJson() const;
  // InputError naming `path` if the text is not a valid record.
  static ScaleRecord FromJson(const std::string& json, const std::string& path);
};

std::string ScaleRecordPath(const std::string& workspace_root);
// The workspace's record; empty if there is none. InputError naming the
// file if it exists but cannot be parsed.
ScaleRecord ReadScaleRecord(const std::string& workspace_root);
// Now, as ISO 8601 UTC with a trailing Z.
std::string CurrentTimeIso8601Utc();

// ---- the transaction ---------------------------------------------------

// Stages replacement files and commits them all at once (see the protocol
// above). Not copyable. If it is destroyed without a successful Commit(),
// it deletes what it staged (the originals never changed).
class CommitTransaction {
 public:
  // Throws InputError if `workspace_root` is not a directory or still holds
  // the journal of an interrupted commit (call RecoverInterruptedCommit()
  // first).
  explicit CommitTransaction(const std::string& workspace_root);
  ~CommitTransaction();
  CommitTransaction(const CommitTransaction&) = delete;
  CommitTransaction& operator=(const CommitTransaction&) = delete;

  // Stages the replacement of `target_path` (which may or may not exist
  // yet; its folder must exist): `write_staged` is called with the staged
  // path and must create that file; it is then fsync'd. If `write_staged`
  // throws, the staged file is removed and the exception propagates.
  // Staging the same target twice replaces the first staged version.
  void Stage(
      const std::string& target_path,
      const std::function<void(const std::string& staged_path)>& write_staged);
  // Stage() with the bytes of the new file; `mode` are its permission bits
  // (default: those of the existing target, else 0644).
  void StageContents(const std::string& target_path,
                     const std::string& contents,
                     int mode = -1);

  // Commits every staged file (protocol steps 2-4). After a failure inside
  // the renames the journal stays and RecoverInterruptedCommit() finishes.
  void Commit();
  // Deletes the staged files; the originals are unchanged. Idempotent.
  void Abort();

  const std::string& workspace_root() const { return root_; }
  // Targets staged so far, in staging order.
  const std::vector<std::string>& targets() const { return targets_; }
  bool committed() const { return committed_; }

 private:
  void RegisterOutsideDir(const std::string& dir);

  std::string root_;
  std::vector<std::string> targets_;
  std::vector<std::string> outside_dirs_;
  bool committed_ = false;
};

// What RecoverInterruptedCommit() did.
struct RecoveryReport {
  enum class Action {
    kNothing,        // no journal, no staged files
    kRolledForward,  // journal found: remaining renames completed
    kRolledBack,     // staged files without journal: deleted
  };
  Action action = Action::kNothing;
  // Targets whose staged file was renamed into place now.
  std::vector<std::string> completed;
  // Staged / temporary files deleted.
  std::vector<std::string> removed;

  // One line for the log, e.g. "finished an interrupted rescale (3 files)".
  std::string Describe() const;
};

// Brings a workspace whose commit was interrupted (crash, kill, power loss)
// to a consistent state: with a journal, every listed target becomes its
// staged version (roll forward; the staged record makes it "rescaled");
// without one, every staged file under the root (and in folders named by the
// staging list) is deleted (roll back). Safe to call on any workspace and to
// repeat. Throws std::runtime_error if a journal target has neither staged
// file nor target (the workspace was changed by hand meanwhile).
RecoveryReport RecoverInterruptedCommit(const std::string& workspace_root);

// The journal of an interrupted commit under `workspace_root` (its path, or
// "" when there is none) and the targets it lists, absolute, in commit
// order. Reads only; InputError naming the journal if it is malformed.
std::string JournalPath(const std::string& workspace_root);
std::vector<std::string> ReadJournalTargets(const std::string& workspace_root);
// A file's staged version (`<target>.dpsfm-staged`).
std::string StagedPath(const std::string& target);

}  // namespace dpsfm
