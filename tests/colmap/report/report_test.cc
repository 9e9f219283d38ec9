// MakeReport on hand-made results: every field it promises, where it reads
// it from, and what a refused run must not claim.
#include "dpsfm/colmap/report/report.h"

#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include <gtest/gtest.h>

namespace dpsfm {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// Two views; view 0 used, view 1 not; three patches of which two selected.
DPScaleResult HandMadeResult() {
  DPScaleResult result;
  result.success = true;
  result.scale = 0.5;
  result.scale_ci_low = 0.45;
  result.scale_ci_high = 0.56;
  result.scale_initial = 0.51;
  result.scale_initial_ci_low = 0.44;
  result.scale_initial_ci_high = 0.58;
  result.intensity.used = true;
  result.intensity.status = "used";
  result.intensity.scale = 0.5;
  result.intensity.ci_low = kNaN;  // JSON has no NaN: null
  result.intensity.ci_high = 0.52;
  result.intensity.failed_evaluations = 3;
  result.intensity.candidate_scales = {0.4, 0.5, 0.6};
  result.intensity.candidate_losses = {2.0, 1.0};  // one short: two points only
  result.cues.dp.valid = true;
  result.cues.dp.scale = 0.5;
  result.cues.dp.ci_low = 0.45;
  result.cues.dp.ci_high = 0.56;
  result.cues.source = "DP data";
  result.cues.dp_data_alone = true;  // worded by refusal_text's CombinationText
  result.views.resize(2);
  result.views[0].name = "a.jpg";
  result.views[0].used = true;
  result.views[0].reason = "used";
  result.views[0].focus_distance_m = 1.25;
  result.views[0].lens.focal_length_mm = 50;
  result.views[1].name = "b.jpg";
  result.views[1].reason = "too few patches";
  result.views[1].recorded_focus_m = 2.0;
  result.views[1].focus_scale = 0.48;
  PatchSample p;
  p.view = 0;
  p.x = 10;
  p.selected = true;
  p.used = true;
  result.patches.push_back(p);
  p.view = 1;
  p.x = 20;
  p.used = false;
  result.patches.push_back(p);
  p.selected = false;  // not selected: not reported
  result.patches.push_back(p);
  result.num_patches = 2;
  return result;
}

TEST(MakeReport, FieldsOfASuccessfulRun) {
  ViewSource source;
  source.image_name = "a.jpg";
  source.dp.left = "dp/left/a.jpg";
  source.dp.sum = "dp/sum/a.jpg";  // no right view: reported as dp_sum
  source.lens.focal_length_source = "lens.csv line 2";
  source.depth_source = "stereo/depth_maps/a.jpg.geometric.bin";
  DPViewSummary summary;
  summary.name = "b.jpg";
  summary.patch_size = 43;
  summary.rejections = {{"across a depth edge", 7}};
  RunTimings timings;
  timings.total = 12.5;
  const nlohmann::json r =
      MakeReport(HandMadeResult(), {source}, {summary}, timings);

  EXPECT_EQ(r["success"], true);
  EXPECT_FALSE(r.contains("reason"));
  EXPECT_DOUBLE_EQ(r["scale"].get<double>(), 0.5);
  EXPECT_DOUBLE_EQ(r["scale_ci_low"].get<double>(), 0.45);
  EXPECT_DOUBLE_EQ(r["scale_initial_ci"][1].get<double>(), 0.58);
  EXPECT_EQ(r["scale_source"], "dual_pixel");
  EXPECT_EQ(r["cues"]["agreement"], "one cue");
  EXPECT_TRUE(r["cues"]["recorded_focus"]["scale"].is_null());
  EXPECT_EQ(r["intensity"]["failed_evaluations"], 3);
  EXPECT_TRUE(r["intensity"]["ci"][0].is_null());  // NaN
  ASSERT_EQ(r["intensity"]["loss_curve"].size(), 2u);
  EXPECT_DOUBLE_EQ(r["intensity"]["loss_curve"][1][1].get<double>(), 1.0);

  const nlohmann::json& a = r["views"]["a.jpg"];
  EXPECT_EQ(a["used"], true);
  EXPECT_DOUBLE_EQ(a["focus_distance_m"].get<double>(), 1.25);
  EXPECT_EQ(a["lens"]["sources"]["focal_length_mm"], "lens.csv line 2");
  EXPECT_EQ(a["dp_sum"], "dp/sum/a.jpg");
  EXPECT_FALSE(a.contains("dp_right"));
  EXPECT_FALSE(a.contains("recorded_focus_distance_m"));
  EXPECT_FALSE(a.contains("patch_rejections"));  // no summary for a.jpg
  const nlohmann::json& b = r["views"]["b.jpg"];
  EXPECT_EQ(b["reason"], "too few patches");
  EXPECT_DOUBLE_EQ(b["recorded_focus_distance_m"].get<double>(), 2.0);
  EXPECT_DOUBLE_EQ(b["scale_from_recorded_focus"].get<double>(), 0.48);
  EXPECT_EQ(b["patch_rejections"]["across a depth edge"], 7);
  EXPECT_EQ(b["patch_size"], 43);

  // Only the selected patches, with their view's name.
  ASSERT_EQ(r["patches"].size(), 2u);
  EXPECT_EQ(r["patches"][0]["view"], "a.jpg");
  EXPECT_EQ(r["patches"][1]["view"], "b.jpg");
  EXPECT_EQ(r["patches"][1]["used"], false);
  EXPECT_DOUBLE_EQ(r["timings"]["total"].get<double>(), 12.5);
  // How the answer was formed, worded by refusal_text.
  EXPECT_EQ(r["cues"]["how"], "the DP data alone (no recorded focus)");
}

TEST(MakeReport, ARefusedRunClaimsNoScale) {
  DPScaleResult result = HandMadeResult();
  result.success = false;
  result.refusal.code = ScaleRefusal::kScaleOpen;
  result.refusal.open.cause = OpenScaleCause::kTooFewPatches;
  result.refusal.open.num_rows = 4;
  result.refusal.open.min_total_patches = 10;
  result.refusal.patches.tried = 20;
  result.refusal.patches.usable = 4;
  const nlohmann::json r = MakeReport(result, {}, {}, RunTimings());
  EXPECT_EQ(r["success"], false);
  // The refusal worded by colmap/report/refusal_text: the error line's
  // cause and fix, and the account in full.
  EXPECT_EQ(r["reason"],
            "too few usable patches for a scale (4 in the joint solve, need "
            "10). Add views with more depth range and texture");
  EXPECT_EQ(r["reason_detail"],
            nlohmann::json::array(
                {"too few usable patches for a scale (4 in the joint solve, "
                 "need 10)",
                 "patches over all views: 20 tried, 4 usable. Typical causes: "
                 "sensor noise too strong for the texture, too little defocus "
                 "blur (small aperture, distant subjects), textureless "
                 "surfaces"}));
  // No scale and no interval of it (null, never 0 or a stale value); what
  // the stages computed stays under scale_initial.
  EXPECT_TRUE(r["scale"].is_null());
  EXPECT_TRUE(r["scale_ci_low"].is_null());
  EXPECT_TRUE(r["scale_ci_high"].is_null());
  EXPECT_DOUBLE_EQ(r["scale_initial"].get<double>(), 0.51);
  EXPECT_TRUE(r["views"]["a.jpg"]["focus_distance_m"].is_null());
}

TEST(MakeReport, ARejectedTranslatingDiskIsTheReasonAndThePsfStatus) {
  DPScaleResult result = HandMadeResult();
  result.success = false;
  result.psf.rejected = true;
  result.psf.status.clear();
  result.refusal.code = ScaleRefusal::kTranslatingDiskRejected;
  result.refusal.disk = {"p 2.2 determined", 0.5, 0.75};
  const nlohmann::json r = MakeReport(result, {}, {}, RunTimings());
  const std::string reason = r["reason"];
  EXPECT_EQ(reason.find("the DP data reject the translating disk: the "
                        "profiles they allow put the scale at 0.5 to 0.75 "
                        "times the disk's"),
            0u)
      << reason;
  // The status is the refusal's account in full.
  const std::string detail = r["reason_detail"][0];
  EXPECT_EQ(detail.find("the DP data reject the translating disk "
                        "(--DPScaleEstimator.psf_model translating_disk"),
            0u)
      << detail;
  EXPECT_EQ(r["psf"]["status"], detail);
}

TEST(MakeReport, BothCuesNamedWhenTheyFormedTheAnswer) {
  DPScaleResult result = HandMadeResult();
  result.cues.combined = true;
  result.cues.agreement = CueAgreement::kAgree;
  result.cues.focus.valid = true;
  result.cues.focus.scale = 0.49;
  result.cues.focus.ci_low = 0.42;
  result.cues.focus.ci_high = 0.57;
  result.cues.focus.num_views = 2;
  result.cues.pinned_profile_strength = 1.1;
  result.cues.dp_data_alone = false;
  result.cues.combination = "the cues agree: their inverse-variance mean";
  const nlohmann::json r = MakeReport(result, {}, {}, RunTimings());
  EXPECT_EQ(r["scale_source"], "dual_pixel+recorded_focus");
  EXPECT_EQ(r["cues"]["how"], "the cues agree: their inverse-variance mean");
  EXPECT_EQ(r["cues"]["agreement"], "agree");
  EXPECT_DOUBLE_EQ(r["cues"]["recorded_focus"]["ci"][0].get<double>(), 0.42);
  EXPECT_EQ(r["cues"]["recorded_focus"]["views"], 2);
  EXPECT_DOUBLE_EQ(r["pinned_profile_strength"].get<double>(), 1.1);
}

// The walkthrough's answer came from the two cues: the intensity stage was
// skipped and no profile was fitted (a calibrated one was given). Neither
// may read as a stage that found 0.
TEST(MakeReport, StagesThatDidNotRunAreNullWithTheirStatus) {
  DPScaleResult result = HandMadeResult();
  result.intensity.used = false;
  result.intensity.status =
      "skipped: the DP data alone leave the scale open; it comes from the "
      "recorded focus";
  result.intensity.scale = 0;
  result.intensity.ci_low = 0;
  result.intensity.ci_high = 0;
  result.intensity.candidate_scales.clear();
  result.intensity.candidate_losses.clear();
  result.psf.status = "calibrated profile r6.dpsf";
  const nlohmann::json r = MakeReport(result, {}, {}, RunTimings());
  EXPECT_EQ(r["intensity"]["ran"], false);
  EXPECT_TRUE(r["intensity"]["scale"].is_null()) << r["intensity"];
  EXPECT_TRUE(r["intensity"]["ci"].is_null()) << r["intensity"];
  EXPECT_EQ(r["intensity"]["status"], result.intensity.status);
  EXPECT_TRUE(r["psf"]["fit"].is_null()) << r["psf"];
  EXPECT_EQ(r["psf"]["fit_status"].get<std::string>().find("not run"), 0u);

  result.psf.fit_ran = true;
  result.psf.fit.centroid_offset = 0.2;
  const nlohmann::json fitted = MakeReport(result, {}, {}, RunTimings());
  EXPECT_EQ(fitted["psf"]["fit_status"], "ran");
  EXPECT_DOUBLE_EQ(
      fitted["psf"]["fit"]["centroid_offset_per_radius"].get<double>(), 0.2);
}

// The search bound as the views ended with it, and a measured profile's
// extrapolation, as the core counted them.
TEST(MakeReport, SearchBoundSection) {
  DPScaleResult result = HandMadeResult();
  SearchBoundAccount& b = result.search_bound;
  b.initial_max_radius_px = 4.93;
  b.max_radius_px = 13;
  b.views_grown = 1;
  b.patches_searched = 240;
  b.patches_beyond_bound = 3;
  b.profile_covered_radius_px = 4.93;
  b.samples = 17;
  b.samples_beyond_coverage = 5;
  b.extrapolation_uncertainty = 0.053;
  DPViewSummary summary;
  summary.name = "a.jpg";
  summary.initial_max_radius_px = 4.93;
  summary.max_radius_px = 13;
  summary.search_bound_growths = 2;
  summary.patches_beyond_bound = 3;
  summary.patches_searched = 240;
  const nlohmann::json r = MakeReport(result, {}, {summary}, RunTimings());
  const nlohmann::json& s = r["search_bound"];
  EXPECT_DOUBLE_EQ(s["initial_px"].get<double>(), 4.93);
  EXPECT_DOUBLE_EQ(s["px"].get<double>(), 13);
  EXPECT_EQ(s["views_grown"], 1);
  EXPECT_EQ(s["patches_beyond_bound"], 3);
  EXPECT_EQ(s["limits_answer"], false);
  EXPECT_EQ(s["patches_beyond_coverage"], 5);
  EXPECT_DOUBLE_EQ(s["extrapolation_uncertainty"].get<double>(), 0.053);
  const nlohmann::json& v = r["views"]["a.jpg"]["search_bound"];
  EXPECT_EQ(v["growths"], 2);
  EXPECT_DOUBLE_EQ(v["initial_px"].get<double>(), 4.93);

  result.search_bound.profile_covered_radius_px = 0;  // a model profile
  EXPECT_TRUE(
      MakeReport(
          result, {}, {}, RunTimings())["search_bound"]["profile_covered_px"]
          .is_null());
}

}  // namespace
}  // namespace dpsfm
