#include "dpsfm/colmap/scale_controller.h"

#include <cmath>
#include <iomanip>
#include <sstream>

#include "colmap/util/logging.h"
#include "colmap/util/misc.h"
#include "colmap/util/timer.h"
#include "dpsfm/colmap/workspace.h"

namespace dpsfm {
namespace {

std::string Seconds(double seconds) {
  std::ostringstream text;
  text << std::fixed << std::setprecision(2) << seconds << " s";
  return text.str();
}

}  // namespace

DPScaleController::DPScaleController(const ViewBudgetOptions& budget,
                                     const WorkspaceReader* reader,
                                     DPScaleEstimator* estimator,
                                     bool capture_overlays)
    : budget_(budget),
      reader_(reader),
      estimator_(estimator),
      capture_overlays_(capture_overlays) {
  budget_.Check();
}

std::vector<int> DPScaleController::VisitingOrder() const {
  std::vector<ViewPlacement> placements;
  for (size_t i = 0; i < reader_->NumViews(); ++i) {
    const ViewSource& source = reader_->Source(i);
    ViewPlacement p;
    const colmap::Image& image =
        reader_->reconstruction().Image(source.image_id);
    p.centre = image.ProjectionCenter();
    p.direction = image.ViewingDirection();
    p.camera_id = static_cast<int>(image.CameraId());
    p.f_number = source.lens.lens.f_number;
    placements.push_back(p);
  }
  return SpreadViewOrder(placements);
}

ScaleRun DPScaleController::Run() {
  ScaleRun run;
  const int num_views = static_cast<int>(reader_->NumViews());
  ViewBudget budget(budget_, num_views);
  run.planned = budget.Planned();
  const std::vector<int> order = VisitingOrder();
  colmap::Timer views_timer;
  views_timer.Start();
  // Overlays: the first, middle and last view of those planned.
  const int planned = run.planned;
  for (int k = 0; k < planned; ++k) {
    const int index = order[k];
    colmap::Timer read_timer;
    read_timer.Start();
    const DPView view = reader_->LoadView(index);
    run.timings.read += read_timer.ElapsedSeconds();
    DPViewSummary summary;
    try {
      summary = estimator_->AddView(view);
    } catch (const std::invalid_argument& error) {
      throw InputError("image " + view.name + ": " + error.what());
    }
    run.timings.blur += summary.seconds;
    if (capture_overlays_ &&
        (k == 0 || k == (planned - 1) / 2 || k == planned - 1) &&
        (run.overlay_images.empty() || run.overlay_images.back().first != k)) {
      cv::Mat image;
      cv::Mat(0.5 * (view.left + view.right)).convertTo(image, CV_8U, 255.0);
      run.overlay_images.emplace_back(k, image);
    }
    run.visited.push_back(index);
    const double elapsed = views_timer.ElapsedSeconds();
    LOG(INFO) << "[" << k + 1 << "/" << planned << "] " << view.name << ": "
              << summary.patches_valid << " of " << summary.patches_tried
              << " patches with a blur estimate, " << summary.patches_kept
              << " kept (" << Seconds(summary.seconds) << "; "
              << Seconds(elapsed) << " so far"
              << (k + 1 < planned
                      ? ", at most " +
                            Seconds(elapsed / (k + 1) * (planned - k - 1)) +
                            " to go"
                      : std::string())
              << ")";
    run.summaries.push_back(summary);
    if (budget.IsCheckpoint(k + 1)) {
      colmap::Timer check_timer;
      check_timer.Start();
      const DPScaleResult provisional = estimator_->Estimate();
      Checkpoint checkpoint;
      checkpoint.views = k + 1;
      checkpoint.success = provisional.success;
      checkpoint.scale = provisional.scale;
      checkpoint.ci_low = provisional.scale_ci_low;
      checkpoint.ci_high = provisional.scale_ci_high;
      std::string why;
      const bool stop = budget.Record(checkpoint, &why);
      if (provisional.success) {
        LOG(INFO) << "  after " << k + 1 << " views: scale "
                  << provisional.scale << " (95% interval "
                  << provisional.scale_ci_low << " .. "
                  << provisional.scale_ci_high << "; "
                  << Seconds(check_timer.ElapsedSeconds()) << ")";
      } else {
        LOG(INFO) << "  after " << k + 1 << " views: no scale yet ("
                  << provisional.failure_reason.substr(0, 120) << "; "
                  << Seconds(check_timer.ElapsedSeconds()) << ")";
      }
      if (stop) {
        // The final estimate would repeat this one (the same views).
        run.result = provisional;
        run.stop_reason = why;
        LOG(INFO) << "  " << why << ": " << num_views - (k + 1)
                  << " views left unvisited ("
                  << "--DPScaleEstimator.all_views 1 visits them all)";
        break;
      }
    }
  }
  for (int k = static_cast<int>(run.visited.size()); k < num_views; ++k) {
    run.skipped.push_back(order[k]);
  }
  if (run.stop_reason.empty() && !run.skipped.empty()) {
    std::ostringstream why;
    why << "the view budget (--DPScaleEstimator.max_views " << planned
        << ") was reached before the scale settled";
    run.stop_reason = why.str();
    LOG(INFO) << "  " << run.stop_reason << ": " << run.skipped.size()
              << " views left unvisited";
  }
  run.checkpoints = budget.Checkpoints();

  colmap::PrintHeading2("Scale estimation");
  if (run.checkpoints.empty() ||
      run.checkpoints.back().views != static_cast<int>(run.visited.size())) {
    run.result = estimator_->Estimate();
  } else {
    LOG(INFO) << "  the estimate of the last checkpoint (" << run.visited.size()
              << " views)";
  }
  run.timings.linear = run.result.seconds_linear;
  run.timings.intensity = run.result.seconds_intensity;
  return run;
}

nlohmann::json ViewBudgetReport(const ScaleRun& run,
                                const WorkspaceReader& reader) {
  nlohmann::json out;
  out["views_total"] = reader.NumViews();
  out["views_planned"] = run.planned;
  out["views_visited"] = run.visited.size();
  nlohmann::json order = nlohmann::json::array();
  for (const int i : run.visited) order.push_back(reader.Source(i).image_name);
  out["visited"] = order;
  nlohmann::json skipped = nlohmann::json::array();
  for (const int i : run.skipped) {
    skipped.push_back(reader.Source(i).image_name);
  }
  out["skipped"] = skipped;
  out["stop_reason"] = run.stop_reason;
  nlohmann::json checkpoints = nlohmann::json::array();
  for (const Checkpoint& c : run.checkpoints) {
    nlohmann::json entry = {{"views", c.views}, {"success", c.success}};
    if (c.success) {
      entry["scale"] = c.scale;
      entry["scale_ci"] = {c.ci_low, c.ci_high};
    }
    checkpoints.push_back(entry);
  }
  out["checkpoints"] = checkpoints;
  return out;
}

}  // namespace dpsfm
