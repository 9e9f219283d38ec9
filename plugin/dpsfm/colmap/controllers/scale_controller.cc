#include "dpsfm/colmap/controllers/scale_controller.h"

#include <cmath>
#include <iomanip>
#include <sstream>

#include "colmap/util/logging.h"
#include "colmap/util/misc.h"
#include "colmap/util/timer.h"
#include "dpsfm/colmap/io/database_check.h"
#include "dpsfm/colmap/io/psf_choice.h"
#include "dpsfm/colmap/io/psf_library.h"
#include "dpsfm/colmap/io/view_prefetcher.h"
#include "dpsfm/colmap/io/workspace.h"
#include "dpsfm/colmap/report/refusal_text.h"
#include "dpsfm/colmap/report/report.h"
#include "dpsfm/colmap/report/report_plots.h"
#include "dpsfm/colmap/rescale/rescale.h"
#include "dpsfm/colmap/rescale/rescale_plan.h"
#include "dpsfm/colmap/rescale/transaction.h"
#include "dpsfm/colmap/util/colmap_compat.h"
#include "dpsfm/core/scale/refusal.h"
#include "dpsfm/core/util/check.h"

namespace dpsfm {
namespace {

std::string Seconds(double seconds) {
  std::ostringstream text;
  text << std::fixed << std::setprecision(2) << seconds << " s";
  return text.str();
}

// The report with where the DP profile came from.
nlohmann::json ReportWithSource(nlohmann::json report,
                                const std::string& psf_source) {
  report["psf"]["source"] = psf_source;
  return report;
}

}  // namespace

DPScaleController::DPScaleController(const ViewBudgetOptions& budget,
                                     const WorkspaceReader* reader,
                                     DPScaleEstimator* estimator,
                                     bool capture_overlays,
                                     int prefetch_views,
                                     bool decode_together)
    : budget_(budget),
      reader_(reader),
      estimator_(estimator),
      capture_overlays_(capture_overlays),
      prefetch_views_(prefetch_views),
      decode_together_(decode_together) {
  DPSFM_CHECK_OPTIONS(budget_, "ViewBudgetOptions");
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

namespace {

// The estimator's reduction of each frame to the working resolution.
FrameReduction EstimatorReduction(const DPScaleEstimator* estimator) {
  return FrameReduction{[estimator](const cv::Mat& rows, const cv::Size& size) {
                          return estimator->ReduceFrame(rows, size);
                        },
                        [estimator](const cv::Size& size) {
                          return estimator->ReduceFrameStripRows(size);
                        }};
}

// The view added to the estimate; what the core cannot take is an
// InputError naming the image.
DPViewSummary AddViewNamed(DPScaleEstimator* estimator, const DPView& view) {
  try {
    return estimator->AddView(view);
  } catch (const CheckFailure& error) {
    // A view the core cannot take: its own words, without the check.
    throw InputError("image " + view.name + ": " +
                     (error.message().empty() ? std::string(error.what())
                                              : error.message()));
  } catch (const std::invalid_argument& error) {
    throw InputError("image " + view.name + ": " + error.what());
  }
}

// Overlays: the first, middle and last (k-th) view of those planned, each
// once, 8-bit at the working resolution.
void CaptureOverlay(int k,
                    int planned,
                    const DPView& view,
                    std::vector<OverlayImage>* overlays) {
  if (!(k == 0 || k == (planned - 1) / 2 || k == planned - 1) ||
      !(overlays->empty() || overlays->back().view != k)) {
    return;
  }
  OverlayImage overlay;
  overlay.view = k;
  cv::Mat(0.5 * (view.left + view.right))
      .convertTo(overlay.image, CV_8U, 255.0);
  overlay.frame_size = view.frame_size;
  overlays->push_back(overlay);
}

// "[k/planned] name: ..." with the time so far and the most left to go.
void LogView(int k,
             int planned,
             const std::string& name,
             const DPViewSummary& summary,
             double elapsed) {
  LOG(INFO) << "[" << k + 1 << "/" << planned << "] " << name << ": "
            << summary.patches_valid << " of " << summary.patches_tried
            << " patches with a blur estimate, " << summary.patches_kept
            << " kept (" << Seconds(summary.seconds) << "; " << Seconds(elapsed)
            << " so far"
            << (k + 1 < planned
                    ? ", at most " +
                          Seconds(elapsed / (k + 1) * (planned - k - 1)) +
                          " to go"
                    : std::string())
            << ")";
}

// A checkpoint's estimate, for the log.
void LogCheckpoint(int views,
                   const DPScaleResult& provisional,
                   double seconds) {
  if (provisional.success) {
    LOG(INFO) << "  after " << views << " views: scale " << provisional.scale
              << " (95% interval " << provisional.scale_ci_low << " .. "
              << provisional.scale_ci_high << "; " << Seconds(seconds) << ")";
  } else {
    LOG(INFO) << "  after " << views << " views: no scale yet ("
              << RefusalLine(provisional.refusal) << "; " << Seconds(seconds)
              << ")";
  }
}

// The views never visited, and why when the budget ran out.
void RecordSkipped(const std::vector<int>& order,
                   int num_views,
                   ScaleRun* run) {
  for (int k = static_cast<int>(run->visited.size()); k < num_views; ++k) {
    run->skipped.push_back(order[k]);
  }
  if (run->stop_reason.empty() && !run->skipped.empty()) {
    std::ostringstream why;
    why << "the view budget (--DPScaleEstimator.max_views " << run->planned
        << ") was reached before the scale settled";
    run->stop_reason = why.str();
    LOG(INFO) << "  " << run->stop_reason << ": " << run->skipped.size()
              << " views left unvisited";
  }
}

}  // namespace

ScaleRun DPScaleController::Run() {
  ScaleRun run;
  const int num_views = static_cast<int>(reader_->NumViews());
  ViewBudget budget(budget_, num_views);
  // The checkpoints' searches, read again by the next estimate.
  EstimateCaches caches;
  run.planned = budget.Planned();
  const std::vector<int> order = VisitingOrder();
  VisitViews(order, &budget, &caches, &run);
  RecordSkipped(order, num_views, &run);
  run.checkpoints = budget.Checkpoints();
  FinalEstimate(&caches, &run);
  return run;
}

void DPScaleController::VisitViews(const std::vector<int>& order,
                                   ViewBudget* budget,
                                   EstimateCaches* caches,
                                   ScaleRun* run) {
  colmap::Timer views_timer;
  views_timer.Start();
  const int planned = run->planned;
  // Views are read ahead (decoding and depth maps overlap the blur search),
  // never beyond those planned, and no read starts while a checkpoint
  // decides (the run may end there: with one view read ahead, the default,
  // none is read for a checkpoint that ends it); each frame reduced to the
  // working resolution as soon as it is decoded (a strip at a time where it
  // can be), so a read holds a view's frames as decoded (both at once with
  // decode_together) and a view waiting no more than the search needs.
  ViewPrefetcher prefetcher(
      reader_,
      std::vector<int>(order.begin(), order.begin() + planned),
      prefetch_views_,
      EstimatorReduction(estimator_),
      decode_together_);
  for (int k = 0; k < planned; ++k) {
    // No read starts before a checkpoint's decision: the run may end there.
    ViewPrefetcher::Read read = prefetcher.Next(!budget->IsCheckpoint(k + 1));
    const DPView& view = read.view;
    run->timings.read += read.seconds;
    run->timings.read_wait += read.waited;
    const DPViewSummary summary = AddViewNamed(estimator_, view);
    run->timings.blur += summary.seconds;
    if (capture_overlays_) {
      CaptureOverlay(k, planned, view, &run->overlay_images);
    }
    run->visited.push_back(order[k]);
    LogView(k, planned, view.name, summary, views_timer.ElapsedSeconds());
    run->summaries.push_back(summary);
    // The view's frames and depth map are done with: the checkpoint below
    // runs on what AddView kept.
    read = ViewPrefetcher::Read();
    if (budget->IsCheckpoint(k + 1)) {
      if (RunCheckpoint(k + 1, budget, caches, run)) break;
      prefetcher.Resume();
    }
  }
}

bool DPScaleController::RunCheckpoint(int views,
                                      ViewBudget* budget,
                                      EstimateCaches* caches,
                                      ScaleRun* run) const {
  colmap::Timer check_timer;
  check_timer.Start();
  const DPScaleResult provisional = estimator_->Estimate(caches);
  Checkpoint checkpoint;
  checkpoint.views = views;
  checkpoint.success = provisional.success;
  checkpoint.scale = provisional.scale;
  checkpoint.ci_low = provisional.scale_ci_low;
  checkpoint.ci_high = provisional.scale_ci_high;
  checkpoint.seconds = check_timer.ElapsedSeconds();
  std::string why;
  const bool stop = budget->Record(checkpoint, &why);
  LogCheckpoint(views, provisional, checkpoint.seconds);
  if (stop) {
    // The final estimate would repeat this one (the same views).
    run->result = provisional;
    run->stop_reason = why;
    LOG(INFO) << "  " << why << ": "
              << static_cast<int>(reader_->NumViews()) - views
              << " views left unvisited ("
              << "--DPScaleEstimator.all_views 1 visits them all)";
  }
  return stop;
}

void DPScaleController::FinalEstimate(EstimateCaches* caches,
                                      ScaleRun* run) const {
  LOG_HEADING2("Scale estimation");
  if (run->checkpoints.empty() ||
      run->checkpoints.back().views != static_cast<int>(run->visited.size())) {
    run->result = estimator_->Estimate(caches);
  } else {
    LOG(INFO) << "  the estimate of the last checkpoint ("
              << run->visited.size() << " views)";
  }
  run->timings.linear = run->result.seconds.linear;
  run->timings.intensity = run->result.seconds.intensity;
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
    nlohmann::json entry = {
        {"views", c.views}, {"success", c.success}, {"seconds", c.seconds}};
    if (c.success) {
      entry["scale"] = c.scale;
      entry["scale_ci"] = {c.ci_low, c.ci_high};
    }
    checkpoints.push_back(entry);
  }
  out["checkpoints"] = checkpoints;
  return out;
}

namespace {

// Step 1: a commit cut short by a crash or kill is finished (or rolled
// back) before anything else reads the workspace. True if the interrupted
// run had estimated and staged everything, so finishing its commit was the
// whole job (estimating again would rescale twice).
bool FinishInterruptedCommit(const std::string& root) {
  const RecoveryReport recovery = RecoverInterruptedCommit(root);
  if (recovery.action == RecoveryReport::Action::kRolledForward) {
    const ScaleRecord finished = ReadScaleRecord(root);
    LOG(WARNING) << "Finished an interrupted rescale: " << recovery.Describe();
    if (finished.IsRescaled()) {
      LOG(INFO) << "Scale " << finished.entries.back().scale
                << " metres per model unit (applied "
                << finished.entries.back().time
                << "); the model is now in metres. Record: "
                << ScaleRecordPath(root);
    }
    return true;
  }
  if (recovery.action == RecoveryReport::Action::kRolledBack) {
    LOG(WARNING) << "Rolled back an interrupted rescale: "
                 << recovery.Describe();
  }
  return false;
}

// Step 2: the plan of what the run will write, made before anything is
// read for the estimate: every refusal the rescale could make is made here.
RescalePlan PlanRun(const ScaleRunOptions& options,
                    const WorkspaceLayout& layout,
                    const std::string& root) {
  RescalePlanOptions plan_options;
  plan_options.mode = options.dry_run               ? RescaleMode::kDryRun
                      : options.output_path.empty() ? RescaleMode::kInPlace
                                                    : RescaleMode::kCopy;
  plan_options.workspace_root = root;
  plan_options.output_path = options.output_path;
  plan_options.extra_model_dirs =
      colmap::CSVToVector<std::string>(options.extra_model_paths);
  plan_options.force = options.force;
  plan_options.estimate_model_dir = layout.model_path;
  const RescalePlan plan = PlanRescale(plan_options);
  for (const std::string& warning : plan.warnings) {
    LOG(WARNING) << warning;
  }
  switch (plan.mode) {
    case RescaleMode::kInPlace:
      LOG(INFO) << "Rescale planned in place: " << plan.Summary();
      break;
    case RescaleMode::kCopy:
      LOG(INFO) << "Rescaled copy planned into " << plan.output_path << ": "
                << plan.Summary();
      break;
    case RescaleMode::kDryRun:
      if (plan.refusal.empty()) {
        LOG(INFO) << "Dry run: a rescale in place would write "
                  << plan.Summary();
      } else {
        LOG(WARNING) << "Dry run: a rescale in place would be refused: "
                     << plan.refusal;
      }
      break;
  }
  return plan;
}

// The report's account of the plan: the mode, what a rescale writes or why
// it would be refused, and the staged files a dry run read.
nlohmann::json PlanReport(const RescalePlan& plan) {
  static const char* const kModes[] = {"in_place", "copy", "dry_run"};
  nlohmann::json out;
  out["mode"] = kModes[static_cast<int>(plan.mode)];
  out["files"] = plan.artefacts.size();
  out["refusal"] = plan.refusal;
  out["interrupted_rescale"] = plan.interrupted();
  if (plan.interrupted()) {
    out["journal"] = plan.journal_path;
    out["staged_files_read"] = plan.StagedFilesRead();
  }
  return out;
}

// Step 3: what was read: the database cross-check and each view's lens
// data with its source.
std::vector<ViewSource> LogInputs(const ScaleRunOptions& options,
                                  const WorkspaceReader& reader) {
  if (!options.database_path.empty()) {
    const DatabaseCheck& check = reader.database_check();
    LOG(INFO) << "Database: " << check.num_database_images << " images; "
              << check.missing_images.size()
              << " model images missing from it, "
              << check.camera_mismatches.size()
              << " with a different camera aspect; "
              << check.original_cameras.size() << " original cameras";
    for (const std::string& name : check.missing_images) {
      LOG(WARNING) << "  not in the database: " << name;
    }
    for (const std::string& name : check.camera_mismatches) {
      LOG(WARNING) << "  camera differs from the database's: " << name;
    }
  }
  std::vector<ViewSource> sources;
  for (size_t i = 0; i < reader.NumViews(); ++i) {
    const ViewSource& source = reader.Source(i);
    sources.push_back(source);
    std::ostringstream line;
    line << "  " << source.image_name << ": f "
         << source.lens.lens.focal_length_mm << " mm ("
         << source.lens.focal_length_source << "), f/"
         << source.lens.lens.f_number << " (" << source.lens.f_number_source
         << "), pitch " << source.lens.lens.pixel_pitch_um << " um ("
         << source.lens.pixel_pitch_source << ")";
    if (!source.lens.focus_source.empty()) {
      line << ", focus " << source.lens.lens.recorded_focus_mm / 1000 << " m ("
           << source.lens.focus_source << ")";
    }
    LOG(INFO) << line.str();
  }
  return sources;
}

struct ProfileChoice {
  std::string model, path;
  std::string source;  // for the log and the report
};

// Step 4: the DP profile: the given one, or (auto) a calibrated one from
// the library when every view has the same known camera and lens.
ProfileChoice ChooseProfile(const ScaleRunOptions& options,
                            const std::vector<ViewSource>& sources) {
  ProfileChoice choice;
  choice.model = options.psf_model;
  choice.path = options.psf_path;
  choice.source =
      choice.model == "calibrated" ? "psf_path " + choice.path : choice.model;
  if (choice.model != "auto" || sources.empty()) return choice;
  const std::string& camera = sources[0].lens.camera;
  const std::string& lens = sources[0].lens.lens_model;
  bool same = true;
  for (const ViewSource& source : sources) {
    same =
        same && source.lens.camera == camera && source.lens.lens_model == lens;
  }
  const std::string library = options.psf_library.empty()
                                  ? DefaultProfileLibrary()
                                  : options.psf_library;
  const std::string found =
      same ? FindLibraryProfile(library, camera, lens) : "";
  if (!found.empty()) {
    choice.model = "calibrated";
    choice.path = found;
    choice.source =
        "library " + found + " (camera '" + camera + "', lens '" + lens + "')";
  } else if (same && !camera.empty() && !lens.empty()) {
    LOG(INFO) << "DP PSF: no profile for camera '" << camera << "', lens '"
              << lens << "' in the library " << library;
  }
  return choice;
}

// What 8-bit and lossy DP frames cost, for the log and the report.
std::vector<std::string> FrameWarnings(const DPScaleResult& result) {
  int eight_bit = 0, lossy = 0;
  for (const DPViewResult& view : result.views) {
    eight_bit += view.frames.bits <= 8;
    lossy += view.frames.lossy;
  }
  std::vector<std::string> warnings;
  if (eight_bit > 0) {
    warnings.push_back(
        std::to_string(eight_bit) +
        " view(s) have 8-bit DP frames: they are decoded to linear light, "
        "where 8 bits leave the darker patches coarsely quantised (their "
        "texture reads as noise and fewer patches qualify). 16-bit frames "
        "(DPRSplit output) keep it.");
  }
  if (lossy > 0) {
    warnings.push_back(
        std::to_string(lossy) +
        " view(s) have lossy (JPEG) DP frames: compression removes fine "
        "texture and rings at edges, which biases small blur estimates; "
        "export PNG or TIFF.");
  }
  return warnings;
}

// The search bound as the views ended with it (DPScaleResult::
// search_bound), for the log and the report: a successful run whose
// patches' blur still lies beyond the bound is a warning, with the option
// that searches farther.
std::vector<std::string> SearchBoundWarnings(const DPScaleResult& result) {
  const SearchBoundAccount& b = result.search_bound;
  std::vector<std::string> warnings;
  if (result.success && b.limits) {
    std::ostringstream s;
    s << b.patches_beyond_bound << " of " << b.patches_searched
      << " searched patches have blur beyond the blur-search bound ("
      << std::setprecision(3) << b.max_radius_px << " px"
      << (b.views_grown > 0 ? ", grown from " : "");
    if (b.views_grown > 0) s << b.initial_max_radius_px << " px";
    s << "): the answer rests on the patches nearer the focus; ";
    if (BoundAtProfileCoverage(b.max_radius_px, b.profile_covered_radius_px)) {
      // Beyond twice the covered blur the profile's kernels are a guess:
      // a larger bound reads those patches, wrongly.
      s << "that is twice the blur the DP profile's calibration covered ("
        << b.profile_covered_radius_px
        << " px), and a calibration capture farther from the focus would "
           "cover them";
    } else {
      s << "--DPScaleEstimator.max_radius_px " << b.larger_radius_px
        << " searches farther";
    }
    warnings.push_back(s.str());
  }
  return warnings;
}

// A measured profile extended beyond the blur it was calibrated over: the
// interval already carries it, and there is nothing to do about it short
// of calibrating with more blur, so it is said, not warned.
std::string ProfileCoverageNote(const DPScaleResult& result) {
  const SearchBoundAccount& b = result.search_bound;
  if (!(b.samples_beyond_coverage > 0)) return "";
  std::ostringstream s;
  s << b.samples_beyond_coverage << " of " << b.samples
    << " selected patches have more blur than the DP profile's calibration "
       "covered ("
    << std::setprecision(3) << b.profile_covered_radius_px
    << " px); there its measured kernels are magnified copies, and the "
       "interval carries +-"
    << std::fixed << std::setprecision(1) << 100 * b.extrapolation_uncertainty
    << " % for it";
  return s.str();
}

// Step 6: what the estimate found, per view and overall.
void LogResult(const DPScaleResult& result) {
  const SearchBoundAccount& bound = result.search_bound;
  if (bound.views_grown > 0) {
    LOG(INFO) << "Blur-search bound grown from " << bound.initial_max_radius_px
              << " to " << bound.max_radius_px << " px in " << bound.views_grown
              << " view(s) whose blur reached it";
  }
  const std::string psf_status = PsfStatusText(result);
  if (!psf_status.empty()) {
    LOG(INFO) << "DP PSF: " << psf_status << " ("
              << Seconds(result.seconds.psf_fit) << ")";
  }
  const std::string focus_check = FocusCheckText(result);
  if (!focus_check.empty()) {
    if (result.cues.focus_agrees) {
      LOG(INFO) << "Recorded focus: " << focus_check;
    } else {
      LOG(WARNING) << "Recorded focus: " << focus_check;
    }
  }
  for (const DPViewResult& view : result.views) {
    LOG(INFO) << "  " << view.name << ": " << (view.used ? "used" : "not used")
              << (view.reason.empty() || view.reason == "used"
                      ? std::string()
                      : " (" + view.reason + ")")
              << "; DP frames " << DPEncodingName(view.frames.encoding) << " ("
              << view.frames.encoding_reason << ")";
  }
  for (const std::string& warning : FrameWarnings(result)) {
    LOG(WARNING) << warning;
  }
  for (const std::string& warning : SearchBoundWarnings(result)) {
    LOG(WARNING) << warning;
  }
  const std::string coverage = ProfileCoverageNote(result);
  if (!coverage.empty()) LOG(INFO) << "DP profile: " << coverage;
}

// What the run does with the profile before the scale, for the log.
const char* SelfCalibrationNote(SelfCalibrationOptions::Mode mode) {
  switch (mode) {
    case SelfCalibrationOptions::Mode::kFit:
      return ", self-calibrated from the data before the scale";
    case SelfCalibrationOptions::Mode::kCheck:
      return ", checked against the data before the scale";
    case SelfCalibrationOptions::Mode::kOff:
      break;
  }
  return "";
}

// "Scale S metres per model unit (95 % interval [lo, hi], from <source>)".
std::string ScaleLine(const DPScaleResult& result) {
  std::ostringstream line;
  line << "Scale " << result.scale << " metres per model unit (95 % interval ["
       << result.scale_ci_low << ", " << result.scale_ci_high << "], from the "
       << (result.cues.source.empty() ? std::string("DP data")
                                      : result.cues.source)
       << ")";
  return line.str();
}

// The pictures next to the report (none without one). A picture that could
// not be written is a warning, never an error: the scale does not depend on
// it. Drawn on the estimate's threads.
ReportPlotFiles WritePlots(const ScaleRunOptions& options,
                           const ScaleRun& run,
                           int num_threads) {
  if (options.report_path.empty()) return {};
  const ReportPlotFiles plots =
      WriteReportPlots(run.result,
                       run.overlay_images,
                       options.report_path,
                       run.summaries.empty() ? 0 : run.summaries[0].patch_size,
                       num_threads);
  for (const std::string& plot : plots.written) {
    LOG(INFO) << "Plot: " << plot;
  }
  for (const PlotFailure& failure : plots.failures) {
    LOG(WARNING) << "Plot " << failure.plot << " not written (" << failure.path
                 << "): " << failure.error;
  }
  return plots;
}

// The report's account of the pictures: the paths written and, for each one
// that was not, which and why.
nlohmann::json PlotsReport(const ReportPlotFiles& plots) {
  nlohmann::json failures = nlohmann::json::array();
  for (const PlotFailure& failure : plots.failures) {
    failures.push_back({{"plot", failure.plot},
                        {"path", failure.path},
                        {"error", failure.error}});
  }
  return {{"written", plots.written}, {"failures", failures}};
}

// The report: the estimate, the inputs, the profile's source, the view
// budget, the plan, the pictures, and (after a rescale) what was rescaled.
nlohmann::json RunReport(const ScaleRun& run,
                         const std::vector<ViewSource>& sources,
                         const WorkspaceReader& reader,
                         const std::string& psf_source,
                         const ReportPlotFiles& plots,
                         const RescalePlan& plan) {
  nlohmann::json report = ReportWithSource(
      MakeReport(run.result, sources, run.summaries, run.timings), psf_source);
  report["view_budget"] = ViewBudgetReport(run, reader);
  std::vector<std::string> warnings = plan.warnings;
  if (!plan.refusal.empty()) {
    warnings.push_back("a rescale in place would be refused: " + plan.refusal);
  }
  for (const std::string& warning : FrameWarnings(run.result)) {
    warnings.push_back(warning);
  }
  for (const std::string& warning : SearchBoundWarnings(run.result)) {
    warnings.push_back(warning);
  }
  report["warnings"] = warnings;
  report["rescale_plan"] = PlanReport(plan);
  report["plots"] = PlotsReport(plots);
  return report;
}

// Step 7: the plan executed, in place or into a copy.
RescaleWorkspaceResult Rescale(const ScaleRunOptions& options,
                               const RescalePlan& plan,
                               double scale) {
  LOG_HEADING2(plan.mode == RescaleMode::kInPlace
                   ? "Rescaling the workspace in place"
                   : "Writing a rescaled copy");
  RescaleProvenance provenance;
  provenance.tool_version = "dp-sfm " + DPSFMVersion();
  for (const std::string* input : {&options.workspace_path,
                                   &options.input_path,
                                   &options.dp_image_path,
                                   &options.lens_path,
                                   &options.image_path}) {
    if (!input->empty()) provenance.inputs.push_back(*input);
  }
  const RescaleWorkspaceResult rescaled =
      ExecuteRescalePlan(plan, scale, provenance);
  for (const std::string& file : rescaled.rescaled_files) {
    VLOG(1) << "  rescaled " << file;
  }
  return rescaled;
}

// Step 0: the workspace's layout, the estimate's options checked, and the
// model named in the log.
WorkspaceLayout StartRun(const ScaleRunOptions& options,
                         const DPScaleOptions& core_options) {
  LOG_HEADING1("DP scale estimation");
  const WorkspaceLayout layout = ResolveWorkspaceLayout(options);
  std::string failure;
  if (!core_options.Check(&failure)) {
    throw InputError("invalid DPScaleEstimator option: " + failure);
  }
  LOG(INFO) << "Model: " << layout.model_path << " ("
            << (layout.dense ? "dense workspace" : "sparse model") << ")";
  return layout;
}

// How the workspace is read: the model as the plan checked it, the files
// of an interrupted rescale as it will leave them.
WorkspaceReadOptions ReadOptions(const RescalePlan& plan, int num_threads) {
  WorkspaceReadOptions read;
  read.model_checked = true;
  read.num_threads = num_threads;
  if (plan.interrupted()) {
    read.read_path = [&plan](const std::string& path) {
      return plan.ReadPath(path);
    };
  }
  return read;
}

// Step 4 (continued): the chosen profile's PSF, each view's lens data
// checked against the conditions it was measured under (before the long
// work), and written into the estimate's options.
PsfChoice ApplyProfile(const ScaleRunOptions& options,
                       const WorkspaceReader& reader,
                       const std::vector<ViewSource>& sources,
                       const ProfileChoice& profile,
                       DPScaleOptions* core_options) {
  const PsfChoice psf = MakePsfField(profile.model, profile.path);
  std::vector<ProfileCheckView> check_views;
  for (const ViewSource& source : sources) {
    const colmap::Camera& camera = reader.reconstruction().Camera(
        reader.reconstruction().Image(source.image_id).CameraId());
    check_views.push_back(
        {source.image_name,
         &source.lens,
         static_cast<int>(std::max(camera.width, camera.height))});
  }
  CheckViewsAgainstProfile(psf, check_views, options.profile_applies);
  psf.ApplyTo(core_options);
  std::string failure;
  if (!core_options->Check(&failure)) {
    throw InputError("invalid DPScaleEstimator option with the DP profile " +
                     profile.source + ": " + failure);
  }
  LOG(INFO) << "DP PSF: " << profile.source << " (" << psf.field.Name()
            << SelfCalibrationNote(core_options->self_calibration.mode) << ")";
  return psf;
}

// Step 5: the view loop and the estimate. One thread asked for means no
// reading thread either, and one frame file decoded at a time.
ScaleRun VisitAndEstimate(const ScaleRunOptions& options,
                          int num_threads,
                          const WorkspaceReader& reader,
                          DPScaleEstimator* estimator) {
  const bool one_thread = num_threads == 1;
  DPScaleController controller(options.view_budget,
                               &reader,
                               estimator,
                               !options.report_path.empty(),
                               one_thread ? 0 : options.prefetch_views,
                               !one_thread);
  return controller.Run();
}

// The report written, and where, in the log.
void WriteReport(const std::string& path, const nlohmann::json& report) {
  WriteJsonFile(path, report);
  LOG(INFO) << "Report: " << path;
}

// No scale: the full account before the one line that says what decided.
RunOutcome Refused(const DPScaleResult& result) {
  LOG(INFO) << "No scale; the refusal in full:";
  for (const std::string& line : RefusalAccount(result.refusal)) {
    LOG(INFO) << "  " << line;
  }
  return RunOutcome::Failure("no scale: " + RefusalLine(result.refusal) +
                             "; nothing was changed");
}

// The scale found, the stages' answers and where the time went.
void LogEstimate(const DPScaleResult& result, const RunTimings& timings) {
  LOG(INFO) << "Linear estimate s* = " << result.scale_initial
            << ", final s = " << result.scale << " (95% interval "
            << result.scale_ci_low << " .. " << result.scale_ci_high
            << "; intensity stage: " << result.intensity.status << ")";
  LOG(INFO) << "Timings: read " << Seconds(timings.read) << " ("
            << Seconds(timings.read_wait) << " not overlapped), blur "
            << Seconds(timings.blur) << ", linear " << Seconds(timings.linear)
            << ", intensity " << Seconds(timings.intensity);
}

// A dry run's last line: the scale, and that nothing was changed.
void LogDryRun(const DPScaleResult& result, const RescalePlan& plan) {
  LOG(INFO) << ScaleLine(result) << "; dry run: nothing was changed"
            << (plan.interrupted()
                    ? " (estimated on the state that finishing the "
                      "interrupted rescale will leave: " +
                          std::to_string(plan.StagedFilesRead().size()) +
                          " staged files read)"
                    : std::string());
}

// The report after a rescale: the run's, with what was rescaled.
nlohmann::json RescaledReport(nlohmann::json report,
                              const RescaleWorkspaceResult& rescaled) {
  report["rescaled_files"] = rescaled.rescaled_files;
  report["cumulative_scale"] = rescaled.entry.cumulative_scale;
  report["record_path"] = rescaled.record_path;
  return report;
}

// A rescale's last line: the scale, what was rescaled where, and the record.
void LogRescaled(const ScaleRunOptions& options,
                 const std::string& root,
                 const DPScaleResult& result,
                 double seconds,
                 const RescaleWorkspaceResult& rescaled) {
  LOG(INFO) << ScaleLine(result) << ": " << rescaled.rescaled_files.size()
            << " files rescaled "
            << (options.output_path.empty() ? "in place in " + root
                                            : "into " + options.output_path)
            << " (" << Seconds(seconds)
            << "); the model is now in metres. Record: "
            << rescaled.record_path;
}

}  // namespace

RunOutcome RunScaleEstimation(const ScaleRunOptions& options,
                              DPScaleOptions core_options) {
  colmap::Timer total_timer;
  total_timer.Start();
  const WorkspaceLayout layout = StartRun(options, core_options);
  // The folder whose metric files are rescaled and which holds the record.
  const std::string root =
      layout.dense ? options.workspace_path : options.input_path;
  const bool in_place = !options.dry_run && options.output_path.empty();
  if (in_place && FinishInterruptedCommit(root)) {
    return RunOutcome::Success();
  }
  const RescalePlan plan = PlanRun(options, layout, root);
  const WorkspaceReader reader(
      options, layout, ReadOptions(plan, core_options.num_threads));
  const std::vector<ViewSource> sources = LogInputs(options, reader);

  LOG_HEADING2("Per-patch DP blur estimation");
  const ProfileChoice profile = ChooseProfile(options, sources);
  const PsfChoice psf =
      ApplyProfile(options, reader, sources, profile, &core_options);
  DPScaleEstimator estimator(core_options, psf.field);
  ScaleRun run =
      VisitAndEstimate(options, core_options.num_threads, reader, &estimator);
  const DPScaleResult& result = run.result;
  RunTimings& timings = run.timings;
  LogResult(result);

  // Without a rescale to follow, the report is complete now.
  const bool rescale = result.success && !options.dry_run;
  timings.total = total_timer.ElapsedSeconds();
  const ReportPlotFiles plots =
      WritePlots(options, run, core_options.num_threads);
  if (!options.report_path.empty() && !rescale) {
    WriteReport(options.report_path,
                RunReport(run, sources, reader, profile.source, plots, plan));
  }
  if (!result.success) return Refused(result);
  LogEstimate(result, timings);
  if (options.dry_run) {
    LogDryRun(result, plan);
    return RunOutcome::Success();
  }

  // Step 7: the rescale, and the report with what it wrote.
  colmap::Timer rescale_timer;
  rescale_timer.Start();
  const RescaleWorkspaceResult rescaled = Rescale(options, plan, result.scale);
  timings.rescale = rescale_timer.ElapsedSeconds();
  timings.total = total_timer.ElapsedSeconds();
  if (!options.report_path.empty()) {
    WriteReport(
        options.report_path,
        RescaledReport(
            RunReport(run, sources, reader, profile.source, plots, plan),
            rescaled));
  }
  LogRescaled(options, root, result, timings.rescale, rescaled);
  return RunOutcome::Success();
}

}  // namespace dpsfm
