#include "dpsfm/core/scale/intensity_search.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "dpsfm/core/optics/kernel_grid.h"
#include "dpsfm/core/scale/intensity_loss.h"
#include "tests/core/synthetic_dp.h"

namespace dpsfm {
namespace {

constexpr int kInterior = 51;
constexpr double kMaxRadius = 10;

// A patch of constant depth rendered at its true blur radius, cropped so the
// border pixels are valid (no reflected image borders).
IntensityPatch RenderPatch(const DPPsfModel& psf,
                           double radius,
                           int view,
                           double depth,
                           uint64_t seed,
                           int channels,
                           const test::RenderOptions& render = {}) {
  const int border = psf.KernelRadius(kMaxRadius);
  const int crop = kInterior + 2 * border;
  const int pad = border + 2;
  test::TextureOptions tex;
  tex.channels = channels;
  const cv::Mat sharp =
      test::MakeTexture(cv::Size(crop + 2 * pad, crop + 2 * pad), seed, tex);
  const test::DPPair pair = test::RenderDP(sharp, psf, radius, render);
  IntensityPatch patch;
  patch.view = view;
  patch.depth = depth;
  patch.border = border;
  const cv::Rect roi(pad, pad, crop, crop);
  patch.left = pair.left(roi).clone();
  patch.right = pair.right(roi).clone();
  return patch;
}

// The translating disk rendered WITHOUT the model's kernels: each view is a
// sum of shifted copies of the sharp image (bilinear shifts of a 0.2 px
// grid of points over the disk of radius |r|), weighted as the disk's light
// divides between the photodiodes: sqrt(R^2 - y^2) -+ sign(r) x (for r > 0
// the left view leans to -x, dp_psf.h). An oracle independent of
// TranslatingDiskPsf::Kernels, so the loss's minimum must land at the true
// radius because the kernels are right, not because they were used twice
// ((I * K_l) * K_r = (I * K_r) * K_l holds for any kernels).
IntensityPatch RenderPatchByShifts(double radius, uint64_t seed) {
  const int border = TranslatingDiskPsf().KernelRadius(kMaxRadius);
  const int crop = kInterior + 2 * border;
  const int pad = border + 2;
  test::TextureOptions tex;
  tex.channels = 1;
  const cv::Mat sharp =
      test::MakeTexture(cv::Size(crop + 2 * pad, crop + 2 * pad), seed, tex);
  const double big_r = std::abs(radius);
  const double sign = radius > 0 ? 1.0 : -1.0;
  cv::Mat left = cv::Mat::zeros(sharp.size(), CV_64FC1);
  cv::Mat right = left.clone();
  double total = 0;
  const double step = 0.2;
  for (double y = -big_r + step / 2; y < big_r; y += step) {
    const double half_chord = std::sqrt(big_r * big_r - y * y);
    for (double x = -half_chord + step / 2; x < half_chord; x += step) {
      // A point at the origin images to (x, y): the image moves by (x, y).
      const cv::Matx23d shift(1, 0, x, 0, 1, y);
      cv::Mat moved;
      cv::warpAffine(sharp,
                     moved,
                     shift,
                     sharp.size(),
                     cv::INTER_LINEAR,
                     cv::BORDER_REFLECT_101);
      moved.convertTo(moved, CV_64FC1);
      const double w_left = half_chord - sign * x;
      const double w_right = half_chord + sign * x;
      left += w_left * moved;
      right += w_right * moved;
      total += w_left + w_right;
    }
  }
  IntensityPatch patch;
  patch.view = 0;
  patch.depth = 1.0;
  patch.border = border;
  const cv::Rect roi(pad, pad, crop, crop);
  cv::Mat l, r;
  cv::Mat(left / total)(roi).convertTo(l, CV_32FC1);
  cv::Mat(right / total)(roi).convertTo(r, CV_32FC1);
  patch.left = l;
  patch.right = r;
  return patch;
}

TEST(PatchAlignmentLoss, MinimalAtTrueRadius) {
  const TranslatingDiskPsf psf;
  for (IntensityLoss loss : {IntensityLoss::kPaperL1,
                             IntensityLoss::kL2,
                             IntensityLoss::kNoiseCorrectedL2}) {
    for (double r : {-4.0, -2.5, 2.0, 6.0}) {
      const IntensityPatch patch = RenderPatchByShifts(r, 7);
      // The loss over r +- 1.5 px in 0.1 px steps: its minimum within
      // 0.2 px of the truth.
      double best = 0, best_loss = std::numeric_limits<double>::infinity();
      for (int k = -15; k <= 15; ++k) {
        const double candidate = r + 0.1 * k;
        const double value =
            PatchAlignmentLoss(patch, candidate, psf, loss, kMaxRadius);
        if (value < best_loss) {
          best_loss = value;
          best = candidate;
        }
      }
      EXPECT_NEAR(best, r, 0.2) << IntensityLossName(loss) << " r=" << r;
      // The wrong sign (left and right read the other way) is clearly worse.
      EXPECT_GT(PatchAlignmentLoss(patch, -r, psf, loss, kMaxRadius),
                3 * best_loss)
          << IntensityLossName(loss) << " r=" << r;
    }
  }
}

TEST(PatchAlignmentLoss, GainDifferenceIsAbsorbedByNormalisation) {
  const TranslatingDiskPsf psf;
  test::RenderOptions render;
  render.left_gain = 1.15;
  render.right_gain = 0.85;
  const IntensityPatch patch = RenderPatch(psf, 3.0, 0, 1.0, 9, 3, render);
  EXPECT_NEAR(
      PatchAlignmentLoss(patch, 3.0, psf, IntensityLoss::kPaperL1, kMaxRadius),
      0.0,
      1e-5);
}

TEST(ChannelNoiseSigma, MeasuresAddedNoise) {
  const TranslatingDiskPsf psf;
  test::RenderOptions render;
  render.noise_sigma = 0.01;
  const IntensityPatch patch = RenderPatch(psf, 4.0, 0, 1.0, 3, 3, render);
  for (double s : EstimateChannelNoiseSigma(patch.left)) {
    EXPECT_NEAR(s, 0.01, 0.0015);
  }
}

TEST(PairNoiseSigma, IgnoresSceneAndGain) {
  const TranslatingDiskPsf psf;
  test::RenderOptions render;
  render.noise_sigma = 0.01;
  render.left_gain = 1.1;
  render.right_gain = 0.9;
  for (double r : {0.0, 1.0, 3.0, -6.0}) {
    const IntensityPatch patch = RenderPatch(psf, r, 0, 1.0, 5, 3, render);
    for (double s : EstimatePairNoiseSigma(patch.left, patch.right)) {
      EXPECT_NEAR(s, 0.01, 0.0015) << "r=" << r;
    }
  }
}

// The kernel grid's node statistics give the loss to the exact path's
// precision on a bright, low-contrast, slightly noisy patch, where the loss
// is a small difference of large inner products: the exact path
// (convolution at r, the difference squared and summed in double) is the
// oracle. Inner products accumulated in float, or taken with the views'
// mean in them, were off by percents here.
TEST(IntensityGridLoss, MatchesTheExactLossOnABrightLowContrastPatch) {
  const TranslatingDiskPsf psf;
  IntensityPatch patch = RenderPatch(psf, 4.0, 0, 1.0, 77, 3);
  cv::RNG rng(5);
  for (cv::Mat* view : {&patch.left, &patch.right}) {
    view->convertTo(*view, -1, 0.02, 0.84);  // mean ~0.85, contrast ~2 %
    cv::Mat noise(view->size(), view->type());
    rng.fill(noise, cv::RNG::NORMAL, 0.0, 2e-5);
    *view += noise;
  }
  const intensity::Prepared exact = intensity::Prepare(patch, psf, kMaxRadius);
  const DPKernelGrid grid(
      psf, 0.25, kMaxRadius, cv::Size(kInterior, kInterior));
  intensity::Prepared on_grid = exact;
  on_grid.grid = &grid;
  on_grid.max_abs_radius = grid.Bound();
  const std::vector<double> radii = {-3.0, 1.5, 3.0, 3.75, 4.0, 4.25, 5.0, 7.0};
  intensity::AddIntervals(patch, intensity::IntervalsOf(grid, radii), &on_grid);
  const double far =
      intensity::LossOfPrepared(exact, 7.0, psf, IntensityLoss::kL2);
  for (const double r : radii) {
    const double want =
        intensity::LossOfPrepared(exact, r, psf, IntensityLoss::kL2);
    const double got =
        intensity::LossOfPrepared(on_grid, r, psf, IntensityLoss::kL2);
    // Relative to the loss itself, and at the minimum (noise alone) to
    // the loss away from it.
    EXPECT_NEAR(got, want, 2e-3 * want + 1e-4 * far) << "r = " << r;
  }
  // The minimum is the noise floor, far below the misfit at 3 px.
  EXPECT_LT(
      intensity::LossOfPrepared(exact, 4.0, psf, IntensityLoss::kL2),
      0.1 * intensity::LossOfPrepared(exact, 3.0, psf, IntensityLoss::kL2));
}

// Intervals added in two passes (the refine pass adds the interval below
// one the first prepared) give the losses one pass gives: a node computed
// again for its new neighbour keeps its terms with the next node.
TEST(IntensityGridLoss, IntervalsAddedLaterKeepTheEarlierOnes) {
  const TranslatingDiskPsf psf;
  const IntensityPatch patch = RenderPatch(psf, 4.0, 0, 1.0, 78, 3);
  const DPKernelGrid grid(
      psf, 0.25, kMaxRadius, cv::Size(kInterior, kInterior));
  intensity::Prepared once = intensity::Prepare(patch, psf, kMaxRadius);
  once.grid = &grid;
  once.max_abs_radius = grid.Bound();
  intensity::Prepared twice = once;
  int node = 0;
  double t = 0;
  grid.Locate(4.1, &node, &t);
  intensity::AddIntervals(patch, {node - 1, node}, &once);
  intensity::AddIntervals(patch, {node}, &twice);
  intensity::AddIntervals(patch, {node - 1}, &twice);
  for (const double r : {3.9, 4.05, 4.1, 4.2}) {
    EXPECT_EQ(intensity::LossOfPrepared(twice, r, psf, IntensityLoss::kL2),
              intensity::LossOfPrepared(once, r, psf, IntensityLoss::kL2))
        << "r = " << r;
  }
}

// Views with their own lens and focus; patches at several depths per view.
struct Scene {
  std::vector<IntensityView> views;
  std::vector<IntensityPatch> patches;
  std::vector<double> true_radius;
};

Scene MakeScene(const DPPsfModel& psf,
                double scale,
                int num_views,
                int patches_per_view,
                const test::RenderOptions& render,
                int channels = 3) {
  Scene scene;
  for (int v = 0; v < num_views; ++v) {
    IntensityView view;
    view.lens.focal_length_mm = v % 2 ? 50 : 35;
    view.lens.f_number = v % 2 ? 2.8 : 1.8;
    view.lens.pixel_pitch_um = 5.36;
    view.pixel_pitch_mm = 2 * view.lens.PixelPitchMm();
    view.focus_distance_model = (1.2 + 0.3 * v) / scale;  // metres / s
    scene.views.push_back(view);
    for (int j = 0; j < patches_per_view; ++j) {
      const double depth = view.focus_distance_model *
                           (0.85 + 0.5 * j / std::max(1, patches_per_view - 1));
      const double r = PredictBlurRadiusPx(view.lens,
                                           view.pixel_pitch_mm,
                                           scale,
                                           view.focus_distance_model,
                                           depth);
      test::RenderOptions rv = render;
      rv.noise_seed = 1000 + 17 * v + j;
      scene.patches.push_back(
          RenderPatch(psf, r, v, depth, 50 + 13 * v + j, channels, rv));
      scene.true_radius.push_back(r);
    }
  }
  return scene;
}

TEST(SearchScaleByIntensity, RecoversScaleOnNoiselessPatches) {
  const TranslatingDiskPsf psf;
  const double scale = 0.25;
  const Scene scene = MakeScene(psf, scale, 3, 5, test::RenderOptions());
  for (double r : scene.true_radius) {
    EXPECT_LT(std::abs(r), kMaxRadius - 1);
  }
  IntensitySearchOptions options;
  options.num_bootstrap = 100;
  const IntensitySearchResult result = SearchScaleByIntensity(
      scene.views, scene.patches, scale * 1.12, psf, options);
  ASSERT_TRUE(result.success) << result.failure_reason;
  // Every loss the search asks for can be evaluated: a count above 0 is a
  // real failure, never the top node of a patch's prepared radii.
  EXPECT_EQ(result.num_failed_evaluations, 0);
  EXPECT_FALSE(result.at_boundary);
  EXPECT_NEAR(result.scale / scale, 1.0, 0.003);
  EXPECT_LE(result.scale_ci_low, scale * 1.003);
  EXPECT_GE(result.scale_ci_high, scale * 0.997);
  EXPECT_EQ(result.candidate_scales.size(), result.candidate_losses.size());
  EXPECT_GE(result.candidate_scales.size(), 100u);
  EXPECT_TRUE(std::is_sorted(result.candidate_scales.begin(),
                             result.candidate_scales.end()));
  EXPECT_NEAR(result.candidate_scales.front(), scale * 1.12 * 0.2, 1e-12);
  EXPECT_NEAR(result.candidate_scales.back(), scale * 1.12 * 1.8, 1e-12);
}

// The kernel-grid path (node inner products, kernels interpolated in r)
// and the exact path (the model's kernel at every candidate radius) give
// the same loss curve and minimum on a noisy scene.
TEST(SearchScaleByIntensity, KernelGridMatchesExactKernels) {
  const TranslatingDiskPsf psf;
  const double scale = 0.25;
  test::RenderOptions render;
  render.noise_sigma = 0.01;
  const Scene scene = MakeScene(psf, scale, 3, 5, render);
  IntensitySearchOptions grid_options;
  grid_options.num_bootstrap = 0;
  IntensitySearchOptions exact_options = grid_options;
  exact_options.grid_step_px = 0;
  for (const IntensityLoss loss :
       {IntensityLoss::kRelativeL2, IntensityLoss::kNoiseCorrectedL2}) {
    grid_options.loss = exact_options.loss = loss;
    const IntensitySearchResult grid = SearchScaleByIntensity(
        scene.views, scene.patches, scale * 0.93, psf, grid_options);
    const IntensitySearchResult exact = SearchScaleByIntensity(
        scene.views, scene.patches, scale * 0.93, psf, exact_options);
    ASSERT_TRUE(grid.success && exact.success) << IntensityLossName(loss);
    EXPECT_NEAR(grid.scale / exact.scale, 1.0, 0.002)
        << IntensityLossName(loss);
    EXPECT_NEAR(grid.scale / scale, 1.0, 0.01) << IntensityLossName(loss);
    // The first-pass curves agree point by point (relative to their span).
    ASSERT_GE(grid.candidate_losses.size(), 100u);
    const auto span = std::minmax_element(exact.candidate_losses.begin(),
                                          exact.candidate_losses.end());
    const double range = *span.second - *span.first;
    ASSERT_GT(range, 0);
    for (size_t k = 0; k < 100; k += 9) {
      const size_t g = std::find(grid.candidate_scales.begin(),
                                 grid.candidate_scales.end(),
                                 exact.candidate_scales[k]) -
                       grid.candidate_scales.begin();
      if (g == grid.candidate_scales.size()) continue;
      EXPECT_NEAR(
          grid.candidate_losses[g], exact.candidate_losses[k], 0.03 * range)
          << IntensityLossName(loss) << " at s = " << exact.candidate_scales[k];
    }
  }
}

void ExpectSameAnswer(const IntensitySearchResult& a,
                      const IntensitySearchResult& b) {
  ASSERT_TRUE(a.success && b.success);
  EXPECT_EQ(a.scale, b.scale);
  EXPECT_EQ(a.scale_ci_low, b.scale_ci_low);
  EXPECT_EQ(a.scale_ci_high, b.scale_ci_high);
  EXPECT_EQ(a.bootstrap_support, b.bootstrap_support);
  EXPECT_EQ(a.candidate_scales, b.candidate_scales);
  EXPECT_EQ(a.candidate_losses, b.candidate_losses);
}

// The view budget's checkpoints search the stored crops again, with more
// views and another initial scale: with the statistics an earlier search
// left, a search answers what it answers without them, to the bit (other
// candidates: other nodes, new neighbours' cross terms), and takes those
// of the crops it shares; another profile's kernels take none.
TEST(IntensityStatsCache, ALaterSearchAnswersAsWithoutIt) {
  const TranslatingDiskPsf psf;
  const double scale = 0.25;
  test::RenderOptions render;
  render.noise_sigma = 0.01;
  const Scene scene = MakeScene(psf, scale, 3, 4, render);
  IntensitySearchOptions options;
  options.num_bootstrap = 20;
  std::vector<IntensityPatch> first;
  for (const IntensityPatch& patch : scene.patches) {
    if (patch.view < 2) first.push_back(patch);
  }
  IntensityStatsCache cache;
  const IntensitySearchResult earlier = SearchScaleByIntensity(
      scene.views, first, scale * 0.93, psf, options, &cache);
  ASSERT_TRUE(earlier.success);
  EXPECT_EQ(earlier.num_nodes_reused, 0);
  EXPECT_GT(earlier.num_nodes_computed, 0);
  EXPECT_EQ(cache.NumCrops(), static_cast<int>(first.size()));

  const IntensitySearchResult later = SearchScaleByIntensity(
      scene.views, scene.patches, scale * 0.97, psf, options, &cache);
  const IntensitySearchResult alone = SearchScaleByIntensity(
      scene.views, scene.patches, scale * 0.97, psf, options);
  ExpectSameAnswer(later, alone);
  EXPECT_GT(later.num_nodes_reused, 0);
  EXPECT_GT(later.num_nodes_computed, 0);
  EXPECT_EQ(cache.NumCrops(), static_cast<int>(scene.patches.size()));

  const SplitProfilePsf other(SplitProfileParams::ForCentroidOffset(0.2));
  const IntensitySearchResult other_later = SearchScaleByIntensity(
      scene.views, scene.patches, scale * 0.97, other, options, &cache);
  const IntensitySearchResult other_alone = SearchScaleByIntensity(
      scene.views, scene.patches, scale * 0.97, other, options);
  ExpectSameAnswer(other_later, other_alone);
  EXPECT_EQ(other_later.num_nodes_reused, 0);
}

// A crop is known by its pixels, its border and its grid: the same pixels
// in other buffers are found, pixels changed in place (the same buffer) or
// another border are not, and each answer is the one without the cache.
TEST(IntensityStatsCache, KnowsACropByPixelsBorderAndGrid) {
  const TranslatingDiskPsf psf;
  const double scale = 0.25;
  test::RenderOptions render;
  render.noise_sigma = 0.01;
  const Scene scene = MakeScene(psf, scale, 2, 4, render);
  IntensitySearchOptions options;
  options.num_bootstrap = 20;
  IntensityStatsCache cache;
  ASSERT_TRUE(SearchScaleByIntensity(
                  scene.views, scene.patches, scale, psf, options, &cache)
                  .success);
  auto search = [&](const std::vector<IntensityPatch>& patches) {
    const IntensitySearchResult with = SearchScaleByIntensity(
        scene.views, patches, scale, psf, options, &cache);
    ExpectSameAnswer(
        with,
        SearchScaleByIntensity(scene.views, patches, scale, psf, options));
    return with;
  };
  std::vector<IntensityPatch> copies = scene.patches;
  for (IntensityPatch& p : copies) {
    p.left = p.left.clone();
    p.right = p.right.clone();
  }
  const IntensitySearchResult same = search(copies);
  EXPECT_GT(same.num_nodes_reused, 0);
  EXPECT_EQ(same.num_nodes_computed, 0);

  for (IntensityPatch& p : copies) p.right += cv::Scalar::all(1e-3);
  const IntensitySearchResult changed = search(copies);
  EXPECT_EQ(changed.num_nodes_reused, 0);
  EXPECT_GT(changed.num_nodes_computed, 0);

  for (IntensityPatch& p : copies) ++p.border;
  const IntensitySearchResult bordered = search(copies);
  EXPECT_EQ(bordered.num_nodes_reused, 0);
  EXPECT_GT(bordered.num_nodes_computed, 0);
}

// docs/method.md, "Intensity stage": on noisy data the paper's loss drifts
// towards larger blur (smaller s). Measure both losses on the same noisy
// scene; the noise-aware loss must be within 2 % and no worse than the
// paper's.
TEST(SearchScaleByIntensity, NoiseCorrectedLossRemovesNoiseBias) {
  const TranslatingDiskPsf psf;
  const double scale = 0.5;
  test::RenderOptions render;
  render.noise_sigma = 0.01;
  const Scene scene = MakeScene(psf, scale, 3, 6, render);
  IntensitySearchOptions options;
  options.num_bootstrap = 0;
  double error[3];
  for (IntensityLoss loss : {IntensityLoss::kPaperL1,
                             IntensityLoss::kL2,
                             IntensityLoss::kNoiseCorrectedL2}) {
    options.loss = loss;
    const IntensitySearchResult result = SearchScaleByIntensity(
        scene.views, scene.patches, scale * 0.9, psf, options);
    ASSERT_TRUE(result.success);
    error[static_cast<int>(loss)] = result.scale / scale - 1.0;
    std::printf("noise 0.01, loss %-20s: scale error %+.4f\n",
                IntensityLossName(loss),
                result.scale / scale - 1.0);
  }
  const double corrected =
      error[static_cast<int>(IntensityLoss::kNoiseCorrectedL2)];
  EXPECT_LT(std::abs(corrected), 0.02);
  EXPECT_LE(std::abs(corrected),
            std::abs(error[static_cast<int>(IntensityLoss::kPaperL1)]) + 0.005);
}

TEST(SearchScaleByIntensity, FlagsMinimumAtRangeEdge) {
  const TranslatingDiskPsf psf;
  const double scale = 0.5;
  const Scene scene = MakeScene(psf, scale, 1, 4, test::RenderOptions(), 1);
  IntensitySearchOptions options;
  options.num_candidates = 20;
  options.relative_range = 0.3;
  options.num_bootstrap = 0;
  // True scale far below the searched range [0.7, 1.3] * 2 s.
  const IntensitySearchResult result = SearchScaleByIntensity(
      scene.views, scene.patches, 2 * scale, psf, options);
  ASSERT_TRUE(result.success);
  EXPECT_TRUE(result.at_boundary);
}

TEST(SearchScaleByIntensity, RefusesWithoutInput) {
  const TranslatingDiskPsf psf;
  const IntensitySearchOptions options;
  EXPECT_FALSE(SearchScaleByIntensity({}, {}, 1.0, psf, options).success);
  const Scene scene = MakeScene(psf, 1.0, 1, 2, test::RenderOptions(), 1);
  EXPECT_FALSE(
      SearchScaleByIntensity(scene.views, scene.patches, -1.0, psf, options)
          .success);
  IntensitySearchOptions bad;
  bad.relative_range = 1.0;
  EXPECT_FALSE(bad.Check());
  EXPECT_THROW(
      SearchScaleByIntensity(scene.views, scene.patches, 1.0, psf, bad),
      std::invalid_argument);
}

}  // namespace
}  // namespace dpsfm

namespace dpsfm {
namespace {

// Patches the model cannot fit: a colour channel without scene content (only
// clipped noise, as a renderer bug once produced) and patches whose true blur
// lies far beyond what the crops support. The absolute losses fall with blur
// on such patches, so their sum over many patches drifted to the small-s
// edge of the range; the relative loss must stay near the truth.
TEST(SearchScaleByIntensity, PatchesTheModelCannotFitDoNotDragTheMinimum) {
  const TranslatingDiskPsf psf;
  const double scale = 0.5;
  test::RenderOptions render;
  render.noise_sigma = 0.002;
  Scene scene = MakeScene(psf, scale, 3, 8, render);
  cv::RNG rng(5);
  for (IntensityPatch& patch : scene.patches) {
    for (cv::Mat* image : {&patch.left, &patch.right}) {
      std::vector<cv::Mat> channels;
      cv::split(*image, channels);
      for (int c = 1; c < 3; ++c) {
        cv::Mat noise(channels[c].size(), CV_32FC1);
        rng.fill(noise, cv::RNG::NORMAL, 0.0, 0.002);
        channels[c] = cv::max(noise, 0.0);
      }
      cv::merge(channels, *image);
    }
  }
  // Two patches per view blurred three times beyond the crops' support.
  for (int v = 0; v < 3; ++v) {
    for (int j = 0; j < 2; ++j) {
      test::RenderOptions rv = render;
      rv.noise_seed = 4000 + 10 * v + j;
      IntensityPatch patch = RenderPatch(psf,
                                         j ? 3 * kMaxRadius : -3 * kMaxRadius,
                                         v,
                                         1.0,
                                         700 + 10 * v + j,
                                         3,
                                         rv);
      // Its depth claims a modest blur.
      patch.depth = scene.views[v].focus_distance_model * (j ? 1.2 : 0.9);
      scene.patches.push_back(patch);
    }
  }
  IntensitySearchOptions options;
  options.num_bootstrap = 0;
  options.max_radius_px = kMaxRadius;
  double relative_error = 1;
  for (IntensityLoss loss :
       {IntensityLoss::kNoiseCorrectedL2, IntensityLoss::kRelativeL2}) {
    options.loss = loss;
    const IntensitySearchResult result = SearchScaleByIntensity(
        scene.views, scene.patches, scale * 1.05, psf, options);
    ASSERT_TRUE(result.success);
    std::printf("unfittable patches, loss %-20s: scale error %+.4f%s\n",
                IntensityLossName(loss),
                result.scale / scale - 1.0,
                result.at_boundary ? " (at the range edge)" : "");
    if (loss == IntensityLoss::kRelativeL2) {
      relative_error = result.scale / scale - 1.0;
      EXPECT_FALSE(result.at_boundary);
    }
  }
  EXPECT_LT(std::abs(relative_error), 0.01);
}

}  // namespace
}  // namespace dpsfm
