// What a run will write, decided once before the estimate (PlanRescale) and
// executed as it stands after it (ExecuteRescalePlan).
//
// The plan reads the workspace's state once: the mode (in place, a copy, a
// dry run), the scale record, the journal of an interrupted commit, and
// every artefact to rescale with its treatment, listed and validated once
// (structure, sizes and record counts: everything that does not need the
// scale; the model the estimate reads is also checked for its cross
// references, model_check.h). Every refusal the commit could make is made
// by PlanRescale, so a run refuses before its estimate, never after it.
// After the estimate ExecuteRescalePlan lists, reads and decides nothing
// again: if a planned file changed meanwhile (size or modification time of
// each artefact, the record, the journal), it refuses and writes nothing.
//
// The already-rescaled rule, in one place: in place or a copy of a
// workspace the record says is in metres needs `force`; a dry run warns.
// An interrupted commit (its journal) is recovered in place before planning
// (RecoverInterruptedCommit, transaction.h); a copy from it is refused; a
// dry run reads the state recovery will produce (the staged files the
// journal lists stand in for their targets) and writes nothing.
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "dpsfm/colmap/rescale/rescale.h"
#include "dpsfm/colmap/rescale/transaction.h"

namespace dpsfm {

enum class RescaleMode {
  kInPlace,  // the workspace's own files, in one CommitTransaction
  kCopy,     // a rescaled copy at output_path; the input is only read
  kDryRun,   // nothing is written; the plan says what a rescale would do
};

struct RescalePlanOptions {
  RescaleMode mode = RescaleMode::kInPlace;
  // The folder whose metric files are rescaled and which holds the record.
  std::string workspace_root;
  // kCopy: where the copy goes (must not exist, or be an empty folder).
  std::string output_path;
  // Model folders rescaled with the workspace (ListArtefactsToRescale); for
  // a copy they must lie inside the workspace.
  std::vector<std::string> extra_model_dirs;
  // Consent to rescale a workspace that was already rescaled.
  bool force = false;
  // The model the estimate reads (one of the planned model folders, or ""):
  // its cross references are checked too (CheckModel).
  std::string estimate_model_dir;
};

// What the plan saw of one file; the commit refuses if it changed.
struct FileStamp {
  std::string path;
  bool exists = false;
  uintmax_t size = 0;
  int64_t mtime_ns = 0;
};

// Size and modification time of `path` now (exists false if it is absent).
FileStamp StampFile(const std::string& path);

struct RescalePlan {
  RescaleMode mode = RescaleMode::kInPlace;
  std::string workspace_root;
  std::string output_path;
  std::vector<std::string> extra_model_dirs;
  bool force = false;
  // The scale record as it stands (in a dry run on an interrupted commit:
  // as recovery will leave it).
  ScaleRecord record;
  // An interrupted commit's journal ("" when there is none; only a dry run
  // plans over one) and, for each of its targets, the file that holds the
  // target's content after recovery (its staged version while it waits).
  std::string journal_path;
  std::map<std::string, std::string> recovered_content;
  // Every file to rescale, in commit order, each validated.
  std::vector<Artefact> artefacts;
  // Dry run only: why a rescale in place would be refused ("" if it would
  // not be). In the other modes such a reason is thrown by PlanRescale.
  std::string refusal;
  // For the log and the report (an already-rescaled workspace in a dry
  // run, a dry run over an interrupted commit).
  std::vector<std::string> warnings;
  // Every file the plan read: the artefacts, the record, the journal.
  std::vector<FileStamp> stamps;

  bool interrupted() const { return !journal_path.empty(); }
  // The file whose bytes stand for `path` in this run: `path` itself, or in
  // a dry run over an interrupted commit its staged version.
  std::string ReadPath(const std::string& path) const;
  // The staged files a dry run reads in place of their targets.
  std::vector<std::string> StagedFilesRead() const;
  // "19 files (1 model: images, points3D, frames; 16 depth maps; 1 PLY)".
  std::string Summary() const;
};

// Makes the plan, or throws InputError with the one reason the run cannot
// rescale as asked (in place and copy modes; a dry run records it in
// `refusal` and goes on). InputError for a journal in place: recover first.
RescalePlan PlanRescale(const RescalePlanOptions& options);

struct RescaleWorkspaceResult {
  // The files written with scaled values (not the record), in the
  // rescaled workspace.
  std::vector<std::string> rescaled_files;
  // The entry added to the record.
  ScaleRecordEntry entry;
  std::string record_path;
};

// What the record entry says of the run.
struct RescaleProvenance {
  std::vector<std::string> inputs;  // what the scale was estimated from
  std::string tool_version;
};

// Executes an in-place or copy plan with `scale`: in place, every artefact
// and the extended record in one CommitTransaction; a copy is built in
// `<output_path>.dpsfm-staging` and renamed to `output_path` at the end
// (never a half copy there; symbolic links copied as links; staged files
// and journals not copied). Throws InputError, having written nothing, if a
// planned file changed since PlanRescale; std::logic_error for a dry run.
RescaleWorkspaceResult ExecuteRescalePlan(const RescalePlan& plan,
                                          double scale,
                                          const RescaleProvenance& provenance);

// ---- plan and execute in one call (scripts, tests) --------------------------

struct RescaleWorkspaceOptions {
  std::vector<std::string> extra_model_dirs;
  bool force = false;
  std::vector<std::string> inputs;
  std::string tool_version;
};

// PlanRescale + ExecuteRescalePlan in place. Call RecoverInterruptedCommit()
// before it.
RescaleWorkspaceResult RescaleWorkspaceInPlace(
    const std::string& workspace_root,
    double scale,
    const RescaleWorkspaceOptions& options);

// PlanRescale + ExecuteRescalePlan into a copy at `output_path`.
RescaleWorkspaceResult WriteRescaledCopy(
    const std::string& workspace_root,
    const std::string& output_path,
    double scale,
    const RescaleWorkspaceOptions& options);

}  // namespace dpsfm
