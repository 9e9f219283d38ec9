// The run of `colmap dp_scale_estimator` between reading the workspace and
// writing results: the view loop, its order and stopping rule
// (core/view_budget.h), progress, and what the report needs from it. The
// command file parses options, builds the reader and the estimator, calls
// Run and prints; the rescale follows in the command.
#pragma once

#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

#include "dpsfm/colmap/report.h"
#include "dpsfm/colmap/workspace_reader.h"
#include "dpsfm/core/dp_scale_estimator.h"
#include "dpsfm/core/view_budget.h"

namespace dpsfm {

struct ScaleRun {
  DPScaleResult result;
  std::vector<DPViewSummary> summaries;  // visited views, in visiting order
  // A few visited views' images (8-bit) for the report's patch overlays.
  std::vector<std::pair<int, cv::Mat>> overlay_images;
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
                    bool capture_overlays);

  // Visits views in SpreadViewOrder until the budget's rule stops, then
  // estimates. Throws InputError naming the image for malformed input.
  ScaleRun Run();

 private:
  std::vector<int> VisitingOrder() const;

  ViewBudgetOptions budget_;
  const WorkspaceReader* reader_;
  DPScaleEstimator* estimator_;
  bool capture_overlays_;
};

// The report's "view_budget" section: visited, planned and skipped views,
// why the run stopped, and the checkpoints' scales.
nlohmann::json ViewBudgetReport(const ScaleRun& run,
                                const WorkspaceReader& reader);

}  // namespace dpsfm
