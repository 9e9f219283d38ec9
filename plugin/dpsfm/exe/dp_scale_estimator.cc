#include "dpsfm/exe/dp_scale_estimator.h"

#include <cstdlib>
#include <exception>
#include <iomanip>
#include <iostream>
#include <memory>
#include <sstream>

#include "colmap/controllers/option_manager.h"
#include "colmap/util/logging.h"
#include "colmap/util/misc.h"
#include "colmap/util/timer.h"
#include "dpsfm/colmap/database_check.h"
#include "dpsfm/colmap/psf_profile.h"
#include "dpsfm/colmap/report.h"
#include "dpsfm/colmap/report_plots.h"
#include "dpsfm/colmap/scale_controller.h"
#include "dpsfm/colmap/transaction.h"
#include "dpsfm/colmap/workspace.h"
#include "dpsfm/colmap/workspace_reader.h"
#include "dpsfm/core/dp_psf.h"
#include "dpsfm/core/dp_scale_estimator.h"

namespace dpsfm {
namespace {

// The one line a failed run leaves on stderr (besides earlier progress).
int Fail(const std::string& message) {
  std::cerr << "ERROR: dp_scale_estimator: " << message << std::endl;
  return EXIT_FAILURE;
}

std::string FormatSeconds(double seconds) {
  std::ostringstream text;
  text << std::fixed << std::setprecision(2) << seconds << " s";
  return text.str();
}

void AddCommandOptions(colmap::OptionManager* manager,
                       DPScaleEstimatorOptions* options,
                       DPScaleOptions* core) {
  manager->AddDefaultOption("workspace_path",
                            &options->workspace_path,
                            "COLMAP dense workspace to rescale");
  manager->AddDefaultOption("input_path",
                            &options->input_path,
                            "sparse model to use instead of a dense workspace");
  manager->AddRequiredOption(
      "dp_image_path",
      &options->dp_image_path,
      "DP views: left/<name> with right/<name> or sum/<name>");
  manager->AddDefaultOption(
      "image_path", &options->image_path, "original images (EXIF lens data)");
  manager->AddDefaultOption(
      "database_path", &options->database_path, "project database, read only");
  manager->AddDefaultOption(
      "original_model_path",
      &options->original_model_path,
      "dense mode: the distorted model image_undistorter was run on (its "
      "cameras map depths into the DP frames' geometry)");
  manager->AddDefaultOption(
      "lens_path", &options->lens_path, "lens.csv with per-image lens data");
  manager->AddDefaultOption("input_type",
                            &options->input_type,
                            "{geometric, photometric} depth maps");
  manager->AddDefaultOption(
      "report_path", &options->report_path, "JSON report to write");
  manager->AddDefaultOption(
      "dry_run", &options->dry_run, "estimate and report, change nothing");
  manager->AddDefaultOption(
      "output_path",
      &options->output_path,
      "write a rescaled copy here instead of rescaling in place");
  manager->AddDefaultOption(
      "extra_model_paths",
      &options->extra_model_paths,
      "comma-separated sparse model folders in the same frame to rescale too");
  manager->AddDefaultOption(
      "force",
      &options->force,
      "rescale a workspace that was already rescaled (composes the scales)");
  manager->AddDefaultOption("DPScaleEstimator.focal_length_mm",
                            &options->focal_length_mm,
                            "focal length in mm for every image");
  manager->AddDefaultOption("DPScaleEstimator.f_number",
                            &options->f_number,
                            "f-number for every image");
  manager->AddDefaultOption("DPScaleEstimator.pixel_pitch_um",
                            &options->pixel_pitch_um,
                            "pixel pitch in um of the model camera's pixels");
  manager->AddDefaultOption(
      "DPScaleEstimator.swap_dp_views",
      &options->swap_dp_views,
      "swap left and right DP views (sensor with the opposite convention)");
  manager->AddDefaultOption(
      "DPScaleEstimator.psf_model",
      &options->psf_model,
      "DP PSF profile: translating_disk (the paper's), calibrated (the file "
      "in psf_path, from dp_psf_calibrator), auto (fitted to the data)");
  manager->AddDefaultOption("DPScaleEstimator.psf_path",
                            &options->psf_path,
                            "DP PSF profile file for psf_model calibrated");
  manager->AddDefaultOption(
      "DPScaleEstimator.psf_library",
      &options->psf_library,
      "folder of calibrated profiles (*.dpsf) picked by camera and lens "
      "with psf_model auto (default: $DPSFM_PROFILE_LIBRARY or "
      "~/.local/share/dp-sfm/profiles)");
  manager->AddDefaultOption(
      "DPScaleEstimator.max_views",
      &options->view_budget.max_views,
      "views visited at most (0: no cap); each keeps its best patches");
  manager->AddDefaultOption(
      "DPScaleEstimator.min_views",
      &options->view_budget.min_views,
      "views visited before the scale may be declared settled");
  manager->AddDefaultOption(
      "DPScaleEstimator.check_every",
      &options->view_budget.check_every,
      "views between two provisional estimates of the stopping rule");
  manager->AddDefaultOption("DPScaleEstimator.all_views",
                            &options->view_budget.all_views,
                            "visit every view (no stopping rule, no cap)");
  // The method's parameters (paper names in brackets).
  manager->AddDefaultOption("DPScaleEstimator.patch_size",
                            &core->patch_size,
                            "patch side in px of the working frame (0: auto)");
  manager->AddDefaultOption(
      "DPScaleEstimator.stride", &core->stride, "patch stride in px (0: auto)");
  manager->AddDefaultOption("DPScaleEstimator.max_radius_px",
                            &core->max_radius_px,
                            "blur radius search bound in px (0: auto)");
  manager->AddDefaultOption("DPScaleEstimator.top_patch_fraction",
                            &core->top_patch_fraction,
                            "[T_c] fraction of patches kept per view");
  manager->AddDefaultOption("DPScaleEstimator.blur_search_factor",
                            &core->blur_search_factor,
                            "blur search on the best this x T_c share of "
                            "patches (0: all, the paper's order)");
  manager->AddDefaultOption("DPScaleEstimator.min_blur_range_px",
                            &core->linear.min_blur_range_px,
                            "[T_p] views need a wider blur range (px)");
  manager->AddDefaultOption("DPScaleEstimator.num_selected_views",
                            &core->linear.num_selected_views,
                            "[N_v] views nearest the median kept");
  manager->AddDefaultOption("DPScaleEstimator.num_candidates",
                            &core->intensity.num_candidates,
                            "candidate scales of the intensity search");
  manager->AddDefaultOption("DPScaleEstimator.candidate_range",
                            &core->intensity.relative_range,
                            "[T_s] candidates span s* (1 +- this)");
  manager->AddDefaultOption("DPScaleEstimator.intensity_refinement",
                            &core->intensity_refinement,
                            "run the intensity-based search after the "
                            "linear estimate");
  manager->AddDefaultOption(
      "DPScaleEstimator.max_scale_ci_relative_width",
      &core->max_scale_ci_relative_width,
      "refuse when the scale's 95 % interval (data and DP profile) is "
      "wider than this fraction of it");
  manager->AddDefaultOption(
      "DPScaleEstimator.pin_to_recorded_focus",
      &core->pin_to_recorded_focus,
      "when the DP profile leaves the scale open, take it from the recorded "
      "focus distances (lens.csv focus_distance_m, EXIF) instead of refusing");
  manager->AddDefaultOption("DPScaleEstimator.recorded_focus_tolerance",
                            &core->recorded_focus_tolerance,
                            "relative accuracy of recorded focus distances");
  manager->AddDefaultOption("DPScaleEstimator.num_threads",
                            &core->num_threads,
                            "threads (-1: all cores)");
}

// The report with where the DP profile came from.
nlohmann::json ReportWithSource(nlohmann::json report,
                                const std::string& psf_source) {
  report["psf"]["source"] = psf_source;
  return report;
}

}  // namespace

int RunDPScaleEstimator(int argc, char** argv) {
  DPScaleEstimatorOptions options;
  DPScaleOptions core_options;

  colmap::OptionManager option_manager;
  AddCommandOptions(&option_manager, &options, &core_options);
  option_manager.Parse(argc, argv);
  options.num_threads = core_options.num_threads;

  try {
    colmap::Timer total_timer;
    total_timer.Start();
    colmap::PrintHeading1("DP scale estimation");
    const WorkspaceLayout layout = ResolveWorkspaceLayout(options);
    try {
      core_options.Check();
    } catch (const std::invalid_argument& error) {
      throw InputError(std::string("invalid DPScaleEstimator option: ") +
                       error.what());
    }
    LOG(INFO) << "Model: " << layout.model_path << " ("
              << (layout.dense ? "dense workspace" : "sparse model") << ")";

    // The folder whose metric files are rescaled and which holds the record.
    const std::string root =
        layout.dense ? options.workspace_path : options.input_path;
    const bool in_place = !options.dry_run && options.output_path.empty();
    if (in_place) {
      // A commit cut short by a crash or kill is finished (or rolled back)
      // before anything else reads the workspace.
      const RecoveryReport recovery = RecoverInterruptedCommit(root);
      if (recovery.action == RecoveryReport::Action::kRolledForward) {
        // The interrupted run had estimated and staged everything; finishing
        // its commit is the whole job. Estimating again would rescale twice.
        const ScaleRecord finished = ReadScaleRecord(root);
        LOG(WARNING) << "Finished an interrupted rescale: "
                     << recovery.Describe();
        if (finished.IsRescaled()) {
          LOG(INFO) << "Scale " << finished.entries.back().scale
                    << " metres per model unit (applied "
                    << finished.entries.back().time
                    << "); the model is now in metres. Record: "
                    << ScaleRecordPath(root);
        }
        return EXIT_SUCCESS;
      }
      if (recovery.action == RecoveryReport::Action::kRolledBack) {
        LOG(WARNING) << "Rolled back an interrupted rescale: "
                     << recovery.Describe();
      }
    }
    const ScaleRecord record = ReadScaleRecord(root);
    if (record.IsRescaled()) {
      const ScaleRecordEntry& last = record.entries.back();
      std::ostringstream note;
      note << "this workspace was already rescaled by dp_scale_estimator ("
           << record.entries.size() << " time(s), last on " << last.time
           << " by " << last.scale << ", total " << record.CumulativeScale()
           << "; see " << ScaleRecordPath(root) << ")";
      if (in_place && !options.force) {
        throw InputError(note.str() +
                         "; pass --force 1 to apply another scale on top");
      }
      LOG(WARNING) << note.str();
    }

    if (!options.dry_run) {
      // What the rescale at the end would refuse, refused now.
      CheckRescaleIsPossible(
          root,
          colmap::CSVToVector<std::string>(options.extra_model_paths),
          options.output_path);
    }
    const WorkspaceReader reader(options, layout);
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
        line << ", focus " << source.lens.lens.recorded_focus_mm / 1000
             << " m (" << source.lens.focus_source << ")";
      }
      LOG(INFO) << line.str();
    }

    colmap::PrintHeading2("Per-patch DP blur estimation");
    // The profile: the given one, or (auto) a calibrated one from the
    // library when every view has the same known camera and lens.
    std::string psf_model = options.psf_model, psf_path = options.psf_path;
    std::string psf_source =
        psf_model == "calibrated" ? "psf_path " + psf_path : psf_model;
    if (psf_model == "auto" && !sources.empty()) {
      const std::string& camera = sources[0].lens.camera;
      const std::string& lens = sources[0].lens.lens_model;
      bool same = true;
      for (const ViewSource& source : sources) {
        same = same && source.lens.camera == camera &&
               source.lens.lens_model == lens;
      }
      const std::string library = options.psf_library.empty()
                                      ? DefaultProfileLibrary()
                                      : options.psf_library;
      const std::string found =
          same ? FindLibraryProfile(library, camera, lens) : "";
      if (!found.empty()) {
        psf_model = "calibrated";
        psf_path = found;
        psf_source = "library " + found + " (camera '" + camera + "', lens '" +
                     lens + "')";
      } else if (same && !camera.empty() && !lens.empty()) {
        LOG(INFO) << "DP PSF: no profile for camera '" << camera << "', lens '"
                  << lens << "' in the library " << library;
      }
    }
    const DPPsfField psf_field =
        MakePsfField(psf_model, psf_path, &core_options);
    LOG(INFO) << "DP PSF: " << psf_source << " (" << psf_field.Name()
              << (core_options.psf_self_calibration
                      ? ", self-calibrated from the data before the scale"
                      : "")
              << ")";
    DPScaleEstimator estimator(core_options, psf_field);
    DPScaleController controller(
        options.view_budget, &reader, &estimator, !options.report_path.empty());
    ScaleRun run = controller.Run();
    const DPScaleResult& result = run.result;
    RunTimings& timings = run.timings;
    const std::vector<DPViewSummary>& summaries = run.summaries;
    if (!result.psf_status.empty()) {
      LOG(INFO) << "DP PSF: " << result.psf_status << " ("
                << FormatSeconds(result.seconds_psf_fit) << ")";
    }
    if (!result.focus_check.empty()) {
      if (result.focus_agrees) {
        LOG(INFO) << "Recorded focus: " << result.focus_check;
      } else {
        LOG(WARNING) << "Recorded focus: " << result.focus_check;
      }
    }
    for (const DPViewResult& view : result.views) {
      LOG(INFO) << "  " << view.name << ": "
                << (view.used ? "used" : "not used") << " (" << view.reason
                << ")";
    }
    // Without a rescale to follow, the report is complete now.
    const bool rescale = result.success && !options.dry_run;
    timings.total = total_timer.ElapsedSeconds();
    if (!options.report_path.empty()) {
      for (const std::string& plot :
           WriteReportPlots(result,
                            run.overlay_images,
                            options.report_path,
                            summaries.empty() ? 0 : summaries[0].patch_size)) {
        LOG(INFO) << "Plot: " << plot;
      }
    }
    if (!options.report_path.empty() && !rescale) {
      nlohmann::json report = ReportWithSource(
          MakeReport(result, sources, summaries, timings), psf_source);
      report["view_budget"] = ViewBudgetReport(run, reader);
      WriteJsonFile(options.report_path, report);
      LOG(INFO) << "Report: " << options.report_path;
    }
    if (!result.success) {
      return Fail("no scale: " + result.failure_reason +
                  "; nothing was changed");
    }
    LOG(INFO) << "Linear estimate s* = " << result.scale_initial
              << ", final s = " << result.scale << " (95% interval "
              << result.scale_ci_low << " .. " << result.scale_ci_high
              << "; intensity stage: " << result.intensity_status << ")";
    LOG(INFO) << "Timings: read " << FormatSeconds(timings.read) << ", blur "
              << FormatSeconds(timings.blur) << ", linear "
              << FormatSeconds(timings.linear) << ", intensity "
              << FormatSeconds(timings.intensity);

    if (options.dry_run) {
      LOG(INFO) << "Scale " << result.scale
                << " metres per model unit (dry run: nothing was changed)";
      return EXIT_SUCCESS;
    }
    colmap::PrintHeading2(options.output_path.empty()
                              ? "Rescaling the workspace in place"
                              : "Writing a rescaled copy");
    colmap::Timer rescale_timer;
    rescale_timer.Start();
    RescaleWorkspaceOptions rescale_options;
    rescale_options.extra_model_dirs =
        colmap::CSVToVector<std::string>(options.extra_model_paths);
    rescale_options.force = options.force;
    rescale_options.tool_version = "dp-sfm " + DPSFMVersion();
    for (const std::string* input : {&options.workspace_path,
                                     &options.input_path,
                                     &options.dp_image_path,
                                     &options.lens_path,
                                     &options.image_path}) {
      if (!input->empty()) rescale_options.inputs.push_back(*input);
    }
    const RescaleWorkspaceResult rescaled =
        options.output_path.empty()
            ? RescaleWorkspaceInPlace(root, result.scale, rescale_options)
            : WriteRescaledCopy(
                  root, options.output_path, result.scale, rescale_options);
    timings.rescale = rescale_timer.ElapsedSeconds();
    for (const std::string& file : rescaled.rescaled_files) {
      VLOG(1) << "  rescaled " << file;
    }
    timings.total = total_timer.ElapsedSeconds();
    if (!options.report_path.empty()) {
      nlohmann::json report = ReportWithSource(
          MakeReport(result, sources, summaries, timings), psf_source);
      report["view_budget"] = ViewBudgetReport(run, reader);
      report["rescaled_files"] = rescaled.rescaled_files;
      report["cumulative_scale"] = rescaled.entry.cumulative_scale;
      report["record_path"] = rescaled.record_path;
      WriteJsonFile(options.report_path, report);
      LOG(INFO) << "Report: " << options.report_path;
    }
    LOG(INFO) << "Scale " << result.scale
              << " metres per model unit: " << rescaled.rescaled_files.size()
              << " files rescaled "
              << (options.output_path.empty() ? "in place in " + root
                                              : "into " + options.output_path)
              << " (" << FormatSeconds(timings.rescale)
              << "); the model is now in metres. Record: "
              << rescaled.record_path;
    return EXIT_SUCCESS;
  } catch (const InputError& error) {
    return Fail(error.what());
  } catch (const std::exception& error) {
    return Fail(std::string("internal error: ") + error.what());
  }
}

}  // namespace dpsfm
