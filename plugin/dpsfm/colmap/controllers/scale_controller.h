// The run of `colmap dp_scale_estimator` (RunScaleEstimation): recovery,
// reading, the DP profile, the view loop with its order and stopping rule
// (DPScaleController, core/scale/view_budget.h), the report and the rescale.
// The command file only parses options, calls it and prints its one line.
#pragma once

#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

#include "dpsfm/colmap/controllers/run_outcome.h"
#include "dpsfm/colmap/io/workspace_reader.h"
#include "dpsfm/colmap/report/patch_overlay_plot.h"
#include "dpsfm/colmap/report/report.h"
#include "dpsfm/core/scale/scale_estimator.h"
#include "dpsfm/core/scale/view_budget.h"

namespace dpsfm {

struct ScaleRun {
  DPScaleResult result;
  std::vector<DPViewSummary> summaries;  // visited views, in visiting order
  // A few visited views' images (8-bit, at the working resolution) for the
  // report's patch overlays.
  std::vector<OverlayImage> overlay_images;
  RunTimings timings;
  std::vector<int> visited;  // reader indices, in visiting order
  std::vector<int> skipped;  // never visited
  std::string stop_reason;   // why views were skipped (empty: none were)
  std::vector<Checkpoint> checkpoints;
  int planned = 0;
};

class DPScaleController {
 public:
  DPScaleController(const ViewBudgetOptions& budget,
                    const WorkspaceReader* reader,
                    DPScaleEstimator* estimator,
                    bool capture_overlays,
                    int prefetch_views = 1,
                    bool decode_together = false);

  // Visits views in SpreadViewOrder until the budget's rule stops, then
  // estimates. The next prefetch_views views are read (ViewPrefetcher) while
  // a view's blur search runs, with decode_together each view's two frame
  // files at once. Throws InputError naming the image for malformed input.
  ScaleRun Run();

 private:
  // Run's steps, in order.

  // The views in SpreadViewOrder.
  std::vector<int> VisitingOrder() const;
  // The planned views read (ahead, ViewPrefetcher), added to the estimate
  // and logged, with a checkpoint wherever the budget has one, until the
  // budget stops the run or the planned views are done.
  void VisitViews(const std::vector<int>& order,
                  ViewBudget* budget,
                  EstimateCaches* caches,
                  ScaleRun* run);
  // The estimate after `views` views, recorded in the budget and logged;
  // true when the budget stops the run there (its estimate is the result).
  bool RunCheckpoint(int views,
                     ViewBudget* budget,
                     EstimateCaches* caches,
                     ScaleRun* run) const;
  // The estimate of the visited views, unless the last checkpoint made it.
  void FinalEstimate(EstimateCaches* caches, ScaleRun* run) const;

  ViewBudgetOptions budget_;
  const WorkspaceReader* reader_;
  DPScaleEstimator* estimator_;
  bool capture_overlays_;
  int prefetch_views_;
  bool decode_together_;
};

// The whole run after option parsing: finishing an interrupted commit, the
// already-rescaled policy, reading the workspace, choosing the DP profile
// (given, library or auto), the view loop (DPScaleController), the report
// and plots, and the rescale. Throws InputError for what the user must
// fix; the command prints it as its one error line.
RunOutcome RunScaleEstimation(const ScaleRunOptions& options,
                              DPScaleOptions core_options);

// The report's "view_budget" section: visited, planned and skipped views,
// why the run stopped, and the checkpoints' scales.
nlohmann::json ViewBudgetReport(const ScaleRun& run,
                                const WorkspaceReader& reader);

}  // namespace dpsfm
