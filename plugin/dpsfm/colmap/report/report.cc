#include "dpsfm/colmap/report/report.h"

#include <cmath>
#include <map>
#include <stdexcept>

#include "dpsfm/colmap/report/refusal_text.h"
#include "dpsfm/colmap/util/durable_file.h"
#include "dpsfm/colmap/util/input_error.h"

namespace dpsfm {
namespace {

// JSON has no NaN or infinity: unknown numbers become null.
nlohmann::json Number(double value) {
  if (std::isfinite(value)) return value;
  return nullptr;
}

nlohmann::json Interval(double low, double high) {
  return nlohmann::json::array({Number(low), Number(high)});
}

}  // namespace

std::string DPSFMVersion() {
#ifdef DPSFM_VERSION
  return DPSFM_VERSION;
#else
  return "unknown";
#endif
}

namespace {

// "intensity": the intensity stage's status, answer and loss curve.
nlohmann::json IntensitySection(const DPScaleResult& result) {
  nlohmann::json intensity;
  intensity["used"] = result.intensity.used;
  intensity["status"] = result.intensity.status;
  // A stage that did not run has no scale and no interval (null, never 0):
  // its status says why.
  const bool ran = result.intensity.scale > 0;
  intensity["ran"] = ran;
  intensity["scale"] = ran ? Number(result.intensity.scale) : nullptr;
  intensity["ci"] =
      ran && result.intensity.ci_high > 0
          ? Interval(result.intensity.ci_low, result.intensity.ci_high)
          : nullptr;
  intensity["loss"] = result.intensity.loss;
  intensity["failed_evaluations"] = result.intensity.failed_evaluations;
  intensity["node_statistics"] = {
      {"reused", result.intensity.nodes_reused},
      {"computed", result.intensity.nodes_computed}};
  nlohmann::json curve = nlohmann::json::array();
  for (size_t i = 0; i < result.intensity.candidate_scales.size() &&
                     i < result.intensity.candidate_losses.size();
       ++i) {
    curve.push_back({Number(result.intensity.candidate_scales[i]),
                     Number(result.intensity.candidate_losses[i])});
  }
  intensity["loss_curve"] = curve;
  return intensity;
}

// One self-calibration fit (the whole frame's).
nlohmann::json ProfileFit(const SplitProfileFit& fit) {
  nlohmann::json j = {
      {"determined", fit.determined},
      {"at_edge_of_family", fit.at_edge},
      {"translating_disk_kept", fit.translating_disk},
      {"split_exponent", Number(fit.params.split_exponent)},
      {"crosstalk", Number(fit.params.crosstalk)},
      {"centroid_offset_per_radius", Number(fit.centroid_offset)},
      {"centroid_offset_ci",
       Interval(fit.centroid_offset_ci_low, fit.centroid_offset_ci_high)},
      {"consistent_centroid_offsets",
       Interval(fit.consistent_low, fit.consistent_high)},
      {"translating_disk_centroid_offset",
       Number(fit.translating_disk_centroid_offset)},
      {"patches", fit.num_patches},
      {"mean_relative_residual", Number(fit.mean_relative_residual)},
      {"translating_disk_criterion", Number(fit.translating_disk_criterion)},
      {"seconds", fit.seconds}};
  nlohmann::json curve = nlohmann::json::array();
  for (size_t i = 0;
       i < fit.centroid_offsets.size() && i < fit.criterion.size();
       ++i) {
    curve.push_back(
        {Number(fit.centroid_offsets[i]), Number(fit.criterion[i])});
  }
  // Trimmed mean relative residual per centroid offset tried.
  j["criterion_curve"] = curve;
  return j;
}

// "psf": the DP PSF profile the stages used and what self-calibration found.
nlohmann::json PsfSection(const DPScaleResult& result) {
  nlohmann::json psf;
  psf["model"] = result.psf.model;
  psf["self_calibrated"] = result.psf.self_calibrated;
  const std::string status = PsfStatusText(result);
  psf["status"] = status;
  // Self-calibration's fit, or null with why when none ran (a given
  // profile is used as it is).
  psf["fit"] = nullptr;
  psf["fit_status"] = result.psf.fit_ran
                          ? "ran"
                          : "not run: the profile was given "
                            "(--DPScaleEstimator.psf_model calibrated)";
  if (!status.empty() && result.psf.fit_ran) {
    psf["fit"] = ProfileFit(result.psf.fit);
    psf["fit"]["patch_searches"] = {{"reused", result.psf.fit_searches_reused},
                                    {"run", result.psf.fit_searches_run}};
    // A profile that changes across the frame: each column band's fit.
    nlohmann::json bands = nlohmann::json::array();
    for (const SplitProfileFit& band : result.psf.band_fits) {
      bands.push_back(
          {{"translating_disk_kept", band.translating_disk},
           {"split_exponent", Number(band.params.split_exponent)},
           {"crosstalk", Number(band.params.crosstalk)},
           {"centroid_offset_per_radius", Number(band.centroid_offset)},
           {"centroid_offset_ci",
            Interval(band.centroid_offset_ci_low,
                     band.centroid_offset_ci_high)},
           {"consistent_centroid_offsets",
            Interval(band.consistent_low, band.consistent_high)},
           {"patches", band.num_patches}});
    }
    psf["fit"]["bands"] = bands;
  }
  psf["scale_factors_allowed_by_profile"] =
      Interval(result.psf.scale_factor_low, result.psf.scale_factor_high);
  return psf;
}

nlohmann::json CueJson(const ScaleCue& c) {
  nlohmann::json j = {{"valid", c.valid}};
  j["scale"] = c.valid ? Number(c.scale) : nullptr;
  j["ci"] = c.valid ? Interval(c.ci_low, c.ci_high) : nullptr;
  return j;
}

// Where the scale itself came from: the DP data, the recorded focus
// distances, or both (core/scale/scale_cues.h), the two cues themselves,
// and the recorded focus as evidence.
void AddScaleSources(const DPScaleResult& result, nlohmann::json* report) {
  nlohmann::json& r = *report;
  const std::string focus_check = FocusCheckText(result);
  if (!focus_check.empty()) {
    r["focus_check"] = {
        {"scale_from_recorded_focus", Number(result.cues.focus_scale)},
        {"ratio", Number(result.cues.focus_scale_ratio)},
        {"agrees", result.cues.focus_agrees},
        {"status", focus_check}};
  }
  r["scale_source"] =
      result.cues.combined && result.cues.agreement != CueAgreement::kOneCue
          ? "dual_pixel+recorded_focus"
          : (result.cues.scale_from_recorded_focus ? "recorded_focus"
                                                   : "dual_pixel");
  if (result.cues.combined) {
    r["pinned_profile_strength"] = Number(result.cues.pinned_profile_strength);
  }
  r["cues"] = {
      {"dual_pixel", CueJson(result.cues.dp)},
      {"recorded_focus", CueJson(result.cues.focus)},
      {"agreement",
       result.cues.agreement == CueAgreement::kAgree
           ? "agree"
           : (result.cues.agreement == CueAgreement::kDisagree ? "disagree"
                                                               : "one cue")},
      {"how", CombinationText(result)}};
  if (result.cues.focus.valid) {
    r["cues"]["recorded_focus"]["views"] = result.cues.focus.num_views;
  }
  r["lens_geometry_uncertainty"] = Number(result.lens_geometry_uncertainty);
}

// What the COLMAP layer knows of a view: where its lens data, DP frames and
// depth came from.
void AddViewSources(const ViewSource& s, nlohmann::json* entry) {
  nlohmann::json& e = *entry;
  e["lens"]["sources"] = {{"focal_length_mm", s.lens.focal_length_source},
                          {"f_number", s.lens.f_number_source},
                          {"pixel_pitch_um", s.lens.pixel_pitch_source}};
  if (!s.lens.focus_source.empty()) {
    e["lens"]["sources"]["focus_distance_m"] = s.lens.focus_source;
  }
  e["dp_left"] = s.dp.left;
  e[s.dp.right.empty() ? "dp_sum" : "dp_right"] =
      s.dp.right.empty() ? s.dp.sum : s.dp.right;
  e["depth_source"] = s.depth_source;
}

// What the blur stage did with a view.
void AddViewSummary(const DPViewSummary& s, nlohmann::json* entry) {
  nlohmann::json& e = *entry;
  e["blur_seconds"] = s.seconds;
  e["working_size"] = {s.working_size.width, s.working_size.height};
  e["patch_size"] = s.patch_size;
  e["max_radius_px"] = s.max_radius_px;
  e["search_bound"] = {{"initial_px", s.initial_max_radius_px},
                       {"px", s.max_radius_px},
                       {"growths", s.search_bound_growths},
                       {"patches_beyond_bound", s.patches_beyond_bound},
                       {"patches_undetermined", s.patches_undetermined},
                       {"patches_searched", s.patches_searched}};
  nlohmann::json rejections = nlohmann::json::object();
  for (const auto& rejection : s.rejections) {
    rejections[rejection.first] = rejection.second;
  }
  e["patch_rejections"] = rejections;
}

nlohmann::json ViewEntry(const DPScaleResult& result,
                         const DPViewResult& view) {
  nlohmann::json entry;
  entry["used"] = view.used;
  entry["reason"] = view.reason;
  entry["focus_distance_m"] =
      result.success ? Number(view.focus_distance_m) : nullptr;
  if (std::isfinite(view.recorded_focus_m)) {
    entry["recorded_focus_distance_m"] = view.recorded_focus_m;
    entry["scale_from_recorded_focus"] = Number(view.focus_scale);
  }
  entry["frames"] = {{"encoding", DPEncodingName(view.frames.encoding)},
                     {"decided_by", view.frames.encoding_reason},
                     {"bits", view.frames.bits},
                     {"lossy", view.frames.lossy}};
  entry["focus_distance_model"] = Number(view.focus_distance_model);
  entry["single_view_scale"] = Number(view.single_view_scale);
  entry["predicted_blur_range_px"] = Number(view.predicted_blur_range_px);
  entry["median_abs_residual_px"] = Number(view.median_abs_residual_px);
  entry["patches"] = {{"tried", view.patches_tried},
                      {"searched", view.patches_searched},
                      {"valid", view.patches_valid},
                      {"selected", view.patches_selected}};
  entry["lens"] = {{"focal_length_mm", view.lens.focal_length_mm},
                   {"f_number", view.lens.f_number},
                   {"dp_pixel_pitch_um", view.lens.pixel_pitch_um}};
  return entry;
}

// "views": per view by name, with its sources and blur-stage summary when
// the COLMAP layer has them.
nlohmann::json ViewsSection(const DPScaleResult& result,
                            const std::vector<ViewSource>& sources,
                            const std::vector<DPViewSummary>& summaries) {
  std::map<std::string, const ViewSource*> source_by_name;
  for (const ViewSource& source : sources) {
    source_by_name[source.image_name] = &source;
  }
  std::map<std::string, const DPViewSummary*> summary_by_name;
  for (const DPViewSummary& summary : summaries) {
    summary_by_name[summary.name] = &summary;
  }
  nlohmann::json views = nlohmann::json::object();
  for (const DPViewResult& view : result.views) {
    nlohmann::json entry = ViewEntry(result, view);
    const auto source = source_by_name.find(view.name);
    if (source != source_by_name.end()) AddViewSources(*source->second, &entry);
    const auto summary = summary_by_name.find(view.name);
    if (summary != summary_by_name.end()) {
      AddViewSummary(*summary->second, &entry);
    }
    views[view.name] = entry;
  }
  return views;
}

// "patches": the selected patches, with their blur measured and predicted.
nlohmann::json PatchesSection(const DPScaleResult& result) {
  nlohmann::json patches = nlohmann::json::array();
  for (const PatchSample& patch : result.patches) {
    if (!patch.selected) continue;
    patches.push_back(
        {{"view", result.views.at(patch.view).name},
         {"x", patch.x},
         {"y", patch.y},
         {"depth_model", patch.depth},
         {"radius_px", Number(patch.radius_px)},
         {"radius_se_px", Number(patch.radius_se_px)},
         {"predicted_radius_px", Number(patch.predicted_radius_px)},
         {"confidence", Number(patch.confidence)},
         {"used", patch.used}});
  }
  return patches;
}

}  // namespace

// The search bound over all views, and a measured profile's extrapolation
// (DPScaleResult::search_bound).
nlohmann::json SearchBoundSection(const DPScaleResult& result) {
  const SearchBoundAccount& b = result.search_bound;
  nlohmann::json section = {{"initial_px", b.initial_max_radius_px},
                            {"px", b.max_radius_px},
                            {"views_grown", b.views_grown},
                            {"patches_searched", b.patches_searched},
                            {"patches_beyond_bound", b.patches_beyond_bound},
                            {"patches_undetermined", b.patches_undetermined},
                            {"limits_answer", b.limits}};
  section["profile_covered_px"] = b.profile_covered_radius_px > 0
                                      ? Number(b.profile_covered_radius_px)
                                      : nullptr;
  section["patches_beyond_coverage"] = b.samples_beyond_coverage;
  section["extrapolation_uncertainty"] = b.extrapolation_uncertainty;
  return section;
}

nlohmann::json MakeReport(const DPScaleResult& result,
                          const std::vector<ViewSource>& sources,
                          const std::vector<DPViewSummary>& summaries,
                          const RunTimings& timings) {
  nlohmann::json report;
  report["tool"] = "dp-sfm " + DPSFMVersion();
  report["success"] = result.success;
  if (!result.success) {
    // The error line's reason, and the refusal in full.
    report["reason"] = RefusalLine(result.refusal);
    report["reason_detail"] = RefusalAccount(result.refusal);
  }
  report["scale"] = result.success ? Number(result.scale) : nullptr;
  report["scale_initial"] =
      result.scale_initial > 0 ? Number(result.scale_initial) : nullptr;
  // A refused run has no scale and no interval of it (null, never 0); what
  // the stages computed stays under scale_initial and cues.
  report["scale_ci_low"] =
      result.success ? Number(result.scale_ci_low) : nullptr;
  report["scale_ci_high"] =
      result.success ? Number(result.scale_ci_high) : nullptr;
  report["scale_initial_ci"] =
      result.scale_initial > 0
          ? Interval(result.scale_initial_ci_low, result.scale_initial_ci_high)
          : nullptr;
  report["units"] = "scale: metres per model unit (metric = scale * model)";
  report["intensity"] = IntensitySection(result);
  AddScaleSources(result, &report);
  report["psf"] = PsfSection(result);
  report["search_bound"] = SearchBoundSection(result);
  report["views"] = ViewsSection(result, sources, summaries);
  report["num_patches"] = result.num_patches;
  report["num_views_used"] = result.num_views_used;
  report["linear_median_abs_residual_px"] =
      Number(result.linear_median_abs_residual_px);
  report["patches"] = PatchesSection(result);
  report["seconds"] = timings.total;
  report["timings"] = {{"read", timings.read},
                       {"read_wait", timings.read_wait},
                       {"blur", timings.blur},
                       {"linear", timings.linear},
                       {"psf_fit", result.seconds.psf_fit},
                       {"intensity", timings.intensity},
                       {"rescale", timings.rescale},
                       {"total", timings.total}};
  return report;
}

void WriteJsonFile(const std::string& path, const nlohmann::json& json) {
  // Through the one home of durable writes (tmp, fsync, rename): a report
  // is never left half written.
  try {
    WriteFileAtomically(path, json.dump(2) + "\n");
  } catch (const std::runtime_error& error) {
    throw InputError("cannot write " + path + " (" + error.what() + ")");
  }
}

}  // namespace dpsfm
