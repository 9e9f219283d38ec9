// One way of checking options (core/util/check.h): every options struct's
// Check() passes on its defaults, fails on a bad field with a failure text
// that names the field and the value given, and DPSFM_CHECK_OPTIONS turns
// it into std::invalid_argument naming the struct. Nested structs prefix
// the field with their member's name. One case per struct.
#include <functional>
#include <string>

#include <gtest/gtest.h>

#include "dpsfm/core/blur/blur_estimation.h"
#include "dpsfm/core/blur/kernel_estimation.h"
#include "dpsfm/core/calibration/psf_calibration.h"
#include "dpsfm/core/calibration/shape_calibration.h"
#include "dpsfm/core/calibration/target_calibration.h"
#include "dpsfm/core/optics/dp_psf.h"
#include "dpsfm/core/optics/dp_renderer.h"
#include "dpsfm/core/optics/lens_model.h"
#include "dpsfm/core/scale/intensity_search.h"
#include "dpsfm/core/scale/linear_estimator.h"
#include "dpsfm/core/scale/scale_estimator.h"
#include "dpsfm/core/scale/view_budget.h"
#include "dpsfm/core/util/check.h"

namespace dpsfm {
namespace {

// Defaults pass; `spoil` makes them fail with a text containing `expected`.
template <typename Options>
void ExpectCheck(const char* name,
                 Options options,
                 const std::function<void(Options*)>& spoil,
                 const std::string& expected) {
  SCOPED_TRACE(name);
  EXPECT_TRUE(options.Check()) << OptionCheckFailure(options);
  spoil(&options);
  std::string failure;
  EXPECT_FALSE(options.Check(&failure));
  EXPECT_NE(failure.find(expected), std::string::npos) << failure;
  EXPECT_EQ(OptionCheckFailure(options), failure);
  try {
    DPSFM_CHECK_OPTIONS(options, name);
    ADD_FAILURE() << "DPSFM_CHECK_OPTIONS did not throw";
  } catch (const std::invalid_argument& error) {
    EXPECT_EQ(std::string(error.what()),
              std::string("invalid ") + name + ": " + failure);
  }
}

TEST(OptionsCheck, BlurEstimationOptions) {
  ExpectCheck<BlurEstimationOptions>(
      "BlurEstimationOptions",
      {},
      [](auto* o) { o->max_radius_px = 0.5; },
      "max_radius_px >= 1 (got 0.5)");
  // The coarse step must be a multiple of the grid step.
  ExpectCheck<BlurEstimationOptions>(
      "BlurEstimationOptions",
      {},
      [](auto* o) { o->coarse_step_px = 0.6; },
      "(got 0.6)");
}

TEST(OptionsCheck, DPScaleOptionsWithNestedStructs) {
  ExpectCheck<DPScaleOptions>(
      "DPScaleOptions",
      {},
      [](auto* o) { o->patches.top_patch_fraction = 2; },
      "patches.top_patch_fraction");
  ExpectCheck<DPScaleOptions>(
      "DPScaleOptions",
      {},
      [](auto* o) { o->blur.coarse_band = 0; },
      "blur.coarse_band > 0 && coarse_band <= 1 (got 0)");
  ExpectCheck<DPScaleOptions>(
      "DPScaleOptions",
      {},
      [](auto* o) { o->linear.irls.tolerance = -1; },
      "linear.irls.tolerance > 0 (got -1)");
  ExpectCheck<DPScaleOptions>(
      "DPScaleOptions",
      {},
      [](auto* o) { o->intensity.search.num_candidates = 2; },
      "intensity.search.num_candidates >= 3 (got 2)");
  ExpectCheck<DPScaleOptions>(
      "DPScaleOptions",
      {},
      [](auto* o) { o->self_calibration.radius_factor = 5; },
      "self_calibration.radius_factor >= 1 && radius_factor <= 4 (got 5)");
}

TEST(OptionsCheck, PatchGeometryOptions) {
  ExpectCheck<PatchGeometryOptions>(
      "PatchGeometryOptions",
      {},
      [](auto* o) { o->search_bound_share = 0; },
      "search_bound_share > 0 && search_bound_share <= 1 (got 0)");
}

TEST(OptionsCheck, PatchSelectionOptions) {
  ExpectCheck<PatchSelectionOptions>(
      "PatchSelectionOptions",
      {},
      [](auto* o) { o->depth_strata = 0; },
      "depth_strata >= 1 (got 0)");
}

TEST(OptionsCheck, IntensityStageOptions) {
  ExpectCheck<IntensityStageOptions>(
      "IntensityStageOptions",
      {},
      [](auto* o) { o->min_bootstrap_support = 2; },
      "min_bootstrap_support <= 1 (got 2)");
  ExpectCheck<IntensityStageOptions>(
      "IntensityStageOptions",
      {},
      [](auto* o) { o->search.relative_range = 1; },
      "search.relative_range");
}

TEST(OptionsCheck, ScaleIntervalOptions) {
  ExpectCheck<ScaleIntervalOptions>(
      "ScaleIntervalOptions",
      {},
      [](auto* o) { o->min_total_patches = -1; },
      "min_total_patches >= 0 (got -1)");
}

// The profile fit's options are checked only when self-calibration runs.
TEST(OptionsCheck, SelfCalibrationOptions) {
  SelfCalibrationOptions off;
  off.fit.min_patches = -1;
  EXPECT_TRUE(off.Check()) << OptionCheckFailure(off);
  SelfCalibrationOptions fit;
  fit.mode = SelfCalibrationOptions::Mode::kFit;
  ExpectCheck<SelfCalibrationOptions>(
      "SelfCalibrationOptions",
      fit,
      [](auto* o) { o->shape_uncertainty = 1; },
      "shape_uncertainty >= 0 && shape_uncertainty < 1 (got 1)");
  ExpectCheck<SelfCalibrationOptions>(
      "SelfCalibrationOptions",
      fit,
      [](auto* o) { o->fit.min_patches = -1; },
      "fit.min_patches >= 3 (got -1)");
}

TEST(OptionsCheck, IntensitySearchOptions) {
  ExpectCheck<IntensitySearchOptions>(
      "IntensitySearchOptions",
      {},
      [](auto* o) { o->relative_range = 1; },
      "relative_range");
}

TEST(OptionsCheck, DPRenderOptions) {
  ExpectCheck<DPRenderOptions>(
      "DPRenderOptions",
      {},
      [](auto* o) { o->radius_step_px = 0; },
      "radius_step_px > 0.0 (got 0)");
}

TEST(OptionsCheck, KernelEstimationOptions) {
  ExpectCheck<KernelEstimationOptions>(
      "KernelEstimationOptions",
      {},
      [](auto* o) { o->half_size = 30; },
      "half_size >= 1 && half_size <= 24 (got 30)");
}

TEST(OptionsCheck, TargetCalibrationOptions) {
  ExpectCheck<TargetCalibrationOptions>(
      "TargetCalibrationOptions",
      {},
      [](auto* o) { o->num_focus_steps = 3; },
      "num_focus_steps >= 10 (got 3)");
  ExpectCheck<TargetCalibrationOptions>(
      "TargetCalibrationOptions",
      {},
      [](auto* o) { o->blur.grid_step_px = 2; },
      "blur.");
}

TEST(OptionsCheck, ShapeCalibrationOptions) {
  ExpectCheck<ShapeCalibrationOptions>(
      "ShapeCalibrationOptions",
      {},
      [](auto* o) { o->max_light_ratio = 0.1; },
      "max_light_ratio > min_light_ratio (got 0.1)");
  ExpectCheck<ShapeCalibrationOptions>(
      "ShapeCalibrationOptions",
      {},
      [](auto* o) { o->layout.rows = 0; },
      "layout.rows >= 1 (got 0)");
}

TEST(OptionsCheck, SplitProfileParams) {
  ExpectCheck<SplitProfileParams>(
      "SplitProfileParams",
      {},
      [](auto* o) { o->crosstalk = 0.5; },
      "crosstalk");
}

TEST(OptionsCheck, DPPsfLayout) {
  ExpectCheck<DPPsfLayout>(
      "DPPsfLayout", {}, [](auto* o) { o->x1 = 1.5; }, "(got 1.5)");
}

TEST(OptionsCheck, ViewBudgetOptions) {
  ExpectCheck<ViewBudgetOptions>(
      "ViewBudgetOptions",
      {},
      [](auto* o) { o->max_views = 5; },
      "max_views == 0 || max_views >= min_views (got 5)");
}

TEST(OptionsCheck, SplitProfileFitOptions) {
  ExpectCheck<SplitProfileFitOptions>(
      "SplitProfileFitOptions",
      {},
      [](auto* o) { o->trim_fraction = 1; },
      "trim_fraction");
}

TEST(OptionsCheck, DPLensData) {
  DPLensData lens;
  lens.focal_length_mm = 50;
  lens.f_number = 2.8;
  lens.pixel_pitch_um = 5.36;
  ExpectCheck<DPLensData>(
      "DPLensData", lens, [](auto* o) { o->f_number = -2; }, "(got -2)");
}

TEST(OptionsCheck, IrlsOptions) {
  ExpectCheck<IrlsOptions>(
      "IrlsOptions",
      {},
      [](auto* o) { o->max_iterations = 0; },
      "max_iterations > 0 (got 0)");
}

TEST(OptionsCheck, LinearEstimatorOptions) {
  ExpectCheck<LinearEstimatorOptions>(
      "LinearEstimatorOptions",
      {},
      [](auto* o) { o->min_samples_per_view = 1; },
      "min_samples_per_view >= 2 (got 1)");
}

TEST(OptionsCheck, FailureIsReturnedToTheCallerOnly) {
  // Each Check() answers for its own struct: no failure is kept between
  // calls (the old per-thread failure text leaked from one check to the
  // next).
  ViewBudgetOptions a;
  a.min_views = 0;
  std::string failure_a;
  EXPECT_FALSE(a.Check(&failure_a));
  EXPECT_NE(failure_a.find("min_views"), std::string::npos) << failure_a;
  IrlsOptions b;
  b.epsilon = 0;
  std::string failure_b = "untouched";
  EXPECT_FALSE(b.Check(&failure_b));
  EXPECT_EQ(failure_b.find("min_views"), std::string::npos) << failure_b;
  EXPECT_NE(failure_b.find("epsilon"), std::string::npos) << failure_b;
  // A passing check leaves the caller's text alone and needs none.
  std::string untouched = "untouched";
  EXPECT_TRUE(IrlsOptions().Check(&untouched));
  EXPECT_EQ(untouched, "untouched");
  EXPECT_TRUE(IrlsOptions().Check());
  EXPECT_FALSE(b.Check());
  // A nested struct's failure is prefixed with its field.
  DPScaleOptions nested;
  nested.linear.irls.epsilon = 0;
  EXPECT_EQ(OptionCheckFailure(nested).find("linear.irls.epsilon"), 0u)
      << OptionCheckFailure(nested);
}

}  // namespace
}  // namespace dpsfm
