#include "dpsfm/core/scale/linear_estimator.h"

#include <cmath>
#include <cstdio>
#include <random>
#include <utility>

#include <gtest/gtest.h>

namespace dpsfm {
namespace {

// The blur radius the data are made from, written out here from the thin
// lens rather than taken from lens_model.h (whose functions the estimator
// solves with: a formula wrong in both would otherwise pass). Aperture
// L = f / N; blur circle on the sensor b = L f (z - g) / (z (g - f)), b > 0
// farther than the focal plane; radius r = b / (2 pitch). Lengths in mm; s
// in metres per model unit, so g = 1000 s g' and z = 1000 s z' in mm.
double ThinLensRadiusPx(double focal_mm,
                        double f_number,
                        double pitch_mm,
                        double scale,
                        double focus_model,
                        double depth_model) {
  const double g = 1000 * scale * focus_model;
  const double z = 1000 * scale * depth_model;
  const double aperture = focal_mm / f_number;
  const double b = aperture * focal_mm * (z - g) / (z * (g - focal_mm));
  return b / (2 * pitch_mm);
}

TEST(ThinLensRadiusPx, HandComputedValue) {
  // 50 mm f/1.8 (L = 27.778 mm), focus 1.5 m, object 3 m: b = 27.778 * 50 *
  // 1500 / (3000 * 1450) = 0.478927 mm; on 10.72 um pixels (5.36 um resized
  // by 0.5) r = 0.478927 / 0.02144 = 22.3380 px; s = 0.25 m per model unit
  // puts them at g' = 6, z' = 12.
  EXPECT_NEAR(ThinLensRadiusPx(50, 1.8, 0.01072, 0.25, 6, 12),
              22.338022531023043,
              1e-9);
}

// A view with its own lens (multi-camera), focus g' and depths around it;
// the radii from ThinLensRadiusPx. `focus_model` (optional) receives the
// view's true g'.
LinearViewData MakeView(int index,
                        double scale,
                        int num_samples,
                        std::mt19937* rng,
                        double* focus_model = nullptr) {
  LinearViewData view;
  view.name = "view" + std::to_string(index);
  const double focals[] = {35, 50, 85, 4.38};
  const double fnums[] = {1.8, 2.8, 1.4, 1.73};
  const double pitches_um[] = {5.36, 5.36, 5.36, 2.8};
  const int k = index % 4;
  view.lens.focal_length_mm = focals[k];
  view.lens.f_number = fnums[k];
  view.lens.pixel_pitch_um = pitches_um[k];
  // Frames resized by 0.5 (the phone's not): pixels twice the pitch.
  view.pixel_pitch_mm = pitches_um[k] * 1e-3 * (k == 3 ? 1 : 2);
  // Focus between 1 and 3 m (0.3-0.6 m for the phone), in model units.
  std::uniform_real_distribution<double> u(0, 1);
  const double g_m = k == 3 ? 0.3 + 0.3 * u(*rng) : 1.0 + 2.0 * u(*rng);
  const double g_model = g_m / scale;
  if (focus_model != nullptr) *focus_model = g_model;
  const double depth_spread = 0.6;
  for (int j = 0; j < num_samples; ++j) {
    const double z_model =
        g_model * (1.0 - depth_spread + 2 * depth_spread * u(*rng)) + 1e-6;
    LinearSample s;
    s.depth = z_model;
    s.radius_px = ThinLensRadiusPx(
        focals[k], fnums[k], view.pixel_pitch_mm, scale, g_model, z_model);
    view.samples.push_back(s);
  }
  return view;
}

// One row of the linear system by hand: f = 50 mm, N = 2 (L = 25 mm), pixels
// of 5 um, r = 3 px at z' = 4. b = 2 r p = 0.03 mm; the row b z'/f =
// z' (b + L) gbar - L sbar divided by 2 p z' / f = 0.04 / 50:
//   gamma   = z' (b + L) f / (2 p z') = 25.03 * 50 / 0.01 = 125150,
//   minus_l = -L f / (2 p z')         = -1250 / 0.04     = -31250,
//   rhs     = b z' / f * f / (2 p z') = b / (2 p)        = 3.
TEST(LinearRow, CoefficientsByHand) {
  DPLensData lens;
  lens.focal_length_mm = 50;
  lens.f_number = 2;
  lens.pixel_pitch_um = 5;
  const LinearRow row = MakeLinearRow(lens, 0.005, 3.0, 4.0);
  EXPECT_NEAR(row.gamma, 125150, 1e-8);
  EXPECT_NEAR(row.minus_l, -31250, 1e-9);
  EXPECT_NEAR(row.rhs, 3, 1e-12);
}

TEST(Irls, ExactOnNoiselessSamplesForAnyViewCount) {
  const double scale = 0.137;
  for (int n = 1; n <= 9; ++n) {
    std::mt19937 rng(n);
    std::vector<LinearViewData> views;
    std::vector<double> focus(n);
    for (int i = 0; i < n; ++i) {
      views.push_back(MakeView(i, scale, 12, &rng, &focus[i]));
    }
    DPLinearSystem system;
    system.num_views = n;
    for (int i = 0; i < n; ++i) {
      for (const auto& s : views[i].samples) {
        system.AddRow(
            i,
            MakeLinearRow(
                views[i].lens, views[i].pixel_pitch_mm, s.radius_px, s.depth));
      }
    }
    const IrlsResult fit = SolveL1Irls(system, IrlsOptions());
    ASSERT_TRUE(fit.success) << n;
    // The unknowns against the chosen truth: sbar = 1 / (1000 s) and
    // gbar_i = 1 / g_i = 1 / (1000 s g'_i), in 1/mm.
    EXPECT_NEAR(fit.x[n] * 1000 * scale, 1.0, 1e-7) << n;
    for (int i = 0; i < n; ++i) {
      EXPECT_NEAR(fit.x[i] * 1000 * scale * focus[i], 1.0, 1e-7)
          << "view " << i << " of " << n;
    }
    EXPECT_LT(fit.residuals.cwiseAbs().maxCoeff(), 1e-6);
  }
}

TEST(Irls, MinimalTwoPatchSystem) {
  // Paper: two patches with distinct depths in one view determine s.
  std::mt19937 rng(3);
  double focus = 0;
  LinearViewData view = MakeView(1, 2.5, 2, &rng, &focus);
  DPLinearSystem system;
  system.num_views = 1;
  for (const auto& s : view.samples) {
    system.AddRow(
        0, MakeLinearRow(view.lens, view.pixel_pitch_mm, s.radius_px, s.depth));
  }
  const IrlsResult fit = SolveL1Irls(system, IrlsOptions());
  ASSERT_TRUE(fit.success);
  EXPECT_NEAR(fit.x[1] * 1000 * 2.5, 1.0, 1e-8);
  EXPECT_NEAR(fit.x[0] * 1000 * 2.5 * focus, 1.0, 1e-8);
}

TEST(Irls, RankDeficientWithoutDepthVariation) {
  std::mt19937 rng(4);
  LinearViewData view = MakeView(0, 1.0, 10, &rng);
  DPLinearSystem system;
  system.num_views = 1;
  for (int k = 0; k < 10; ++k) {
    system.AddRow(0,
                  MakeLinearRow(view.lens,
                                view.pixel_pitch_mm,
                                view.samples[0].radius_px,
                                view.samples[0].depth));
  }
  const IrlsResult fit = SolveL1Irls(system, IrlsOptions());
  EXPECT_LT(fit.rcond, 1e-10);
}

TEST(Irls, RecoversScaleWith30PercentGrossOutliers) {
  const double scale = 0.42;
  for (int trial = 0; trial < 5; ++trial) {
    std::mt19937 rng(100 + trial);
    std::normal_distribution<double> noise(0, 0.05);
    // Gross errors of 2-8 px of either sign on 30 % of the patches.
    std::uniform_real_distribution<double> gross(2, 8);
    std::uniform_real_distribution<double> u(0, 1);
    std::vector<LinearViewData> views;
    std::vector<double> focus(4);
    for (int i = 0; i < 4; ++i) {
      views.push_back(MakeView(i, scale, 100, &rng, &focus[i]));
      for (auto& s : views.back().samples) {
        s.radius_px +=
            u(rng) < 0.3 ? (u(rng) < 0.5 ? -1 : 1) * gross(rng) : noise(rng);
      }
    }
    LinearEstimatorOptions options;
    options.num_bootstrap = 50;
    const LinearEstimate est = EstimateScaleLinear(views, options);
    ASSERT_TRUE(est.success) << static_cast<int>(est.failure.cause);
    EXPECT_NEAR(est.scale / scale, 1.0, 0.005) << "trial " << trial;
    for (int i = 0; i < 4; ++i) {
      EXPECT_TRUE(est.views[i].used) << est.views[i].reason;
      EXPECT_NEAR(est.views[i].focus_model / focus[i], 1.0, 0.005)
          << "trial " << trial << ", view " << i;
    }
    EXPECT_LE(est.scale_ci_low, est.scale);
    EXPECT_GE(est.scale_ci_high, est.scale);
  }
}

TEST(SelectViewsNearMedian, CorrectForOneToTenViews) {
  for (int n = 1; n <= 10; ++n) {
    for (int nv : {1, 3, 7}) {
      // Scales 1.0 * 1.1^(k - offset) in shuffled order: the median and its
      // neighbours are known.
      std::vector<double> scales(n);
      std::vector<int> perm(n);
      for (int k = 0; k < n; ++k) perm[k] = k;
      std::mt19937 rng(n * 10 + nv);
      std::shuffle(perm.begin(), perm.end(), rng);
      for (int k = 0; k < n; ++k) scales[perm[k]] = std::pow(1.1, k);
      const std::vector<bool> eligible(n, true);
      const std::vector<int> sel = SelectViewsNearMedian(scales, eligible, nv);
      ASSERT_EQ(static_cast<int>(sel.size()), std::min(n, nv))
          << n << " " << nv;
      // The kept views are a contiguous run of ranks around the median:
      // every kept rank is within the kept count of the middle.
      std::vector<int> rank_of_view(n);
      for (int k = 0; k < n; ++k) rank_of_view[perm[k]] = k;
      std::vector<int> ranks;
      for (int v : sel) ranks.push_back(rank_of_view[v]);
      std::sort(ranks.begin(), ranks.end());
      for (size_t k = 1; k < ranks.size(); ++k) {
        EXPECT_EQ(ranks[k], ranks[k - 1] + 1) << n << " " << nv;
      }
      const double mid = 0.5 * (n - 1);
      const double centre = 0.5 * (ranks.front() + ranks.back());
      EXPECT_LE(std::abs(centre - mid), 0.5 + 1e-9) << n << " " << nv;
      // Sorted and unique.
      EXPECT_TRUE(std::is_sorted(sel.begin(), sel.end()));
    }
  }
}

TEST(SelectViewsNearMedian, SkipsIneligibleAndInvalid) {
  const std::vector<double> scales = {1.0, 100.0, -1.0, 1.1, NAN, 0.9, 50.0};
  const std::vector<bool> eligible = {
      true, true, true, true, true, true, false};
  const std::vector<int> sel = SelectViewsNearMedian(scales, eligible, 3);
  EXPECT_EQ(sel, (std::vector<int>{0, 3, 5}));
}

TEST(EstimateScaleLinear, SelectionRecordsEveryRejection) {
  const double scale = 0.8;
  std::mt19937 rng(7);
  std::vector<LinearViewData> views;
  for (int i = 0; i < 10; ++i) views.push_back(MakeView(i, scale, 30, &rng));
  // View 1: too few patches. View 2: no depth variation (blur varies).
  // View 3: tiny blur.
  // View 4: blur falling with depth (s <= 0).
  views[1].samples.resize(2);
  for (auto& s : views[2].samples) s.depth = views[2].samples[0].depth;
  for (auto& s : views[3].samples) s.radius_px *= 0.05;
  for (auto& s : views[4].samples) s.radius_px = -s.radius_px;
  LinearEstimatorOptions options;
  options.num_selected_views = 4;
  options.num_bootstrap = 20;
  const LinearEstimate est = EstimateScaleLinear(views, options);
  ASSERT_TRUE(est.success) << static_cast<int>(est.failure.cause);
  EXPECT_NEAR(est.scale / scale, 1.0, 1e-6);
  EXPECT_EQ(est.views[1].rejection, ViewRejection::kTooFewPatches);
  EXPECT_EQ(est.views[2].rejection, ViewRejection::kDegenerate);
  EXPECT_EQ(est.views[3].rejection, ViewRejection::kSmallBlurRange);
  EXPECT_TRUE(est.views[4].rejection == ViewRejection::kNonPositiveScale ||
              est.views[4].rejection == ViewRejection::kNonPositiveFocus)
      << est.views[4].reason;
  int used = 0, far = 0;
  for (const auto& v : est.views) {
    EXPECT_FALSE(v.reason.empty());
    used += v.used;
    far += v.rejection == ViewRejection::kFarFromMedian;
  }
  EXPECT_EQ(used, 4);
  EXPECT_EQ(far, 2);
  // Every view with samples gets a focus distance under the joint scale,
  // also the unused ones (view 3 keeps the truth since only its blur scaled).
  for (int i : {0, 5, 6}) {
    EXPECT_TRUE(std::isfinite(est.views[i].focus_model)) << i;
  }
}

TEST(EstimateScaleLinear, FailureSaysWhy) {
  std::mt19937 rng(8);
  std::vector<LinearViewData> views;
  for (int i = 0; i < 12; ++i) {
    views.push_back(MakeView(i, 1.0, 20, &rng));
    for (auto& s : views.back().samples) {
      s.radius_px *= i < 9 ? 1e-4 : -1.0;
    }
  }
  const LinearEstimate est =
      EstimateScaleLinear(views, LinearEstimatorOptions());
  EXPECT_FALSE(est.success);
  // The 9 views of almost no blur are the most frequent rejection, with
  // the threshold T_p = 2 px (the default) that rejected them.
  EXPECT_EQ(est.failure.cause, LinearFailureCause::kNoViewSelected);
  ASSERT_FALSE(est.failure.view_rejections.empty());
  EXPECT_EQ(est.failure.view_rejections[0],
            std::make_pair(9, ViewRejection::kSmallBlurRange));
  EXPECT_DOUBLE_EQ(est.failure.min_blur_range_px, 2);
  EXPECT_FALSE(est.failure.SwappedViewsLikely());
  EXPECT_EQ(EstimateScaleLinear({}, LinearEstimatorOptions()).failure.cause,
            LinearFailureCause::kNoViews);
}

TEST(EstimateScaleLinear, RejectsViewsWhoseBlurIgnoresDepth) {
  // Blur estimates of pure noise: random radii unrelated to depth.
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-9, 9);
  std::vector<LinearViewData> views;
  for (int i = 0; i < 5; ++i) {
    views.push_back(MakeView(i, 1.0, 30, &rng));
    for (auto& s : views.back().samples) s.radius_px = u(rng);
  }
  const LinearEstimate est =
      EstimateScaleLinear(views, LinearEstimatorOptions());
  EXPECT_FALSE(est.success);
  for (const auto& v : est.views) EXPECT_FALSE(v.used) << v.reason;
  EXPECT_EQ(est.failure.cause, LinearFailureCause::kNoViewSelected);
}

TEST(EstimateScaleLinear, SingleViewWorks) {
  std::mt19937 rng(9);
  double focus = 0;
  const LinearEstimate est = EstimateScaleLinear(
      {MakeView(0, 3.0, 20, &rng, &focus)}, LinearEstimatorOptions());
  ASSERT_TRUE(est.success) << static_cast<int>(est.failure.cause);
  EXPECT_NEAR(est.scale / 3.0, 1.0, 1e-7);
  EXPECT_NEAR(est.views[0].focus_model / focus, 1.0, 1e-7);
}

// The bootstrap's resamples are drawn in order and solved in parallel: one
// and two threads give the same interval and focus samples, to the bit
// (another seed gives another interval, so the comparison can fail).
TEST(EstimateScaleLinear, BootstrapTheSameAtAnyThreadCount) {
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0, 0.2);
  std::vector<LinearViewData> views;
  std::vector<double> focus(5);
  for (int i = 0; i < 5; ++i) {
    views.push_back(MakeView(i, 0.42, 60, &rng, &focus[i]));
    for (auto& s : views.back().samples) s.radius_px += noise(rng);
  }
  LinearEstimatorOptions options;
  options.num_bootstrap = 64;
  options.num_threads = 1;
  const LinearEstimate one = EstimateScaleLinear(views, options);
  options.num_threads = 2;
  const LinearEstimate two = EstimateScaleLinear(views, options);
  ASSERT_TRUE(one.success && two.success);
  EXPECT_LT(one.scale_ci_low, one.scale_ci_high);
  EXPECT_EQ(two.scale_ci_low, one.scale_ci_low);
  EXPECT_EQ(two.scale_ci_high, one.scale_ci_high);
  for (int i = 0; i < 5; ++i) {
    const auto& a = one.views[i].focus_model_samples;
    const auto& b = two.views[i].focus_model_samples;
    ASSERT_EQ(a.size(), 64u);
    ASSERT_EQ(b.size(), a.size());
    for (size_t k = 0; k < a.size(); ++k) {
      EXPECT_TRUE(a[k] == b[k] || (std::isnan(a[k]) && std::isnan(b[k])))
          << "view " << i << ", resample " << k;
    }
  }
  options.seed = 43;
  const LinearEstimate other = EstimateScaleLinear(views, options);
  EXPECT_NE(other.scale_ci_low, one.scale_ci_low);
}

TEST(LinearEstimatorOptions, CheckIsActedOn) {
  LinearEstimatorOptions options;
  EXPECT_TRUE(options.Check());
  options.num_threads = 0;
  EXPECT_FALSE(options.Check());
  options.num_threads = -1;
  options.min_samples_per_view = 1;
  EXPECT_FALSE(options.Check());
  EXPECT_THROW(EstimateScaleLinear({}, options), std::invalid_argument);
}

}  // namespace
}  // namespace dpsfm
