// The evidence each searched patch carries (BlurEvidence, radius_se_px):
// measured only where the loss curve determines a minimum beyond what the
// patch's noise gives, beyond the bound only where the loss still falls into
// it, and a standard error that matches the spread of r over noise draws.
// The oracles are independent of the evidence's formula: the truth a patch
// was rendered with, and the empirical spread over noise seeds.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include <gtest/gtest.h>

#include "dpsfm/core/blur/blur_estimation.h"
#include "dpsfm/core/util/statistics.h"
#include "tests/core/synthetic_dp.h"

namespace dpsfm {
namespace {

using test::DPPair;
using test::MakeTexture;
using test::RenderDP;
using test::RenderOptions;

constexpr double kBound = 10;

// The pipeline's crop at a 10 px bound: a 51 px patch and its border.
int Crop(const DPPsfModel& psf) {
  return 51 + 2 * psf.KernelRadius(kBound + 0.5);
}

BlurEstimationOptions Options() {
  BlurEstimationOptions options;
  options.max_radius_px = kBound;
  return options;
}

test::TextureOptions SceneTexture() {
  test::TextureOptions texture;
  texture.coarsest_cell_px = 48;
  texture.octaves = 6;
  texture.shapes_per_10k_px = 6;
  return texture;
}

// A textured patch at blur `radius` (or, with radius_right, its right half
// at another blur: a depth edge down the middle), cropped from a larger
// render so that its border holds real blurred content.
DPPair TexturedPatch(const DPPsfModel& psf,
                     double radius,
                     uint64_t texture_seed,
                     uint64_t noise_seed,
                     double noise_sigma,
                     double radius_right = std::nan("")) {
  const int crop = Crop(psf), margin = 40;
  const cv::Size size(crop + 2 * margin, crop + 2 * margin);
  const cv::Mat sharp = MakeTexture(size, texture_seed, SceneTexture());
  RenderOptions render;
  render.noise_sigma = noise_sigma;
  render.noise_seed = noise_seed;
  DPPair full;
  if (std::isnan(radius_right)) {
    full = RenderDP(sharp, psf, radius, render);
  } else {
    cv::Mat radii(size, CV_32FC1, cv::Scalar(radius));
    radii(cv::Rect(size.width / 2, 0, size.width - size.width / 2, size.height))
        .setTo(radius_right);
    full = RenderDP(sharp, psf, radii, render);
  }
  const cv::Rect r(margin, margin, crop, crop);
  return DPPair{full.left(r).clone(), full.right(r).clone()};
}

// Pure noise: a flat grey patch with independent noise in each view, and a
// textured patch whose two views share nothing (independent textures): in
// neither is there a blur to measure. At most 2 % may come back measured.
TEST(BlurEvidence, PureNoiseIsRarelyMeasured) {
  const TranslatingDiskPsf psf;
  const PatchBlurEstimator estimator(
      psf, Options(), cv::Size(Crop(psf), Crop(psf)));
  const int crop = Crop(psf);
  int measured_flat = 0, measured_textured = 0;
  const int seeds = 200;
  for (int seed = 1; seed <= seeds; ++seed) {
    DPPair flat{cv::Mat(crop, crop, CV_32FC1, cv::Scalar(0.4)),
                cv::Mat(crop, crop, CV_32FC1, cv::Scalar(0.4))};
    RenderOptions render;
    render.noise_sigma = 0.01;
    render.noise_seed = seed;
    test::internal::FinishViews(render, &flat);
    const PatchBlurEstimate f = estimator.Estimate(flat.left, flat.right);
    measured_flat += f.evidence == BlurEvidence::kMeasured;
    EXPECT_EQ(f.valid, f.evidence == BlurEvidence::kMeasured);

    DPPair unrelated{
        MakeTexture(cv::Size(crop, crop), 5000 + seed, SceneTexture()),
        MakeTexture(cv::Size(crop, crop), 9000 + seed, SceneTexture())};
    test::internal::FinishViews(render, &unrelated);
    const PatchBlurEstimate u =
        estimator.Estimate(unrelated.left, unrelated.right);
    measured_textured += u.evidence == BlurEvidence::kMeasured;
    EXPECT_EQ(u.valid, u.evidence == BlurEvidence::kMeasured);
  }
  std::printf("pure noise measured: flat %d of %d, unrelated views %d of %d\n",
              measured_flat,
              seeds,
              measured_textured,
              seeds);
  EXPECT_LE(measured_flat, 0.02 * seeds);
  EXPECT_LE(measured_textured, 0.02 * seeds);
}

// The same textures with a blur the views do share are measured: the rule
// is not simply "refuse everything".
TEST(BlurEvidence, TexturedBlurIsMeasured) {
  const TranslatingDiskPsf psf;
  const PatchBlurEstimator estimator(
      psf, Options(), cv::Size(Crop(psf), Crop(psf)));
  int measured = 0, tried = 0;
  for (const double radius : {-6.0, -2.5, 0.0, 1.5, 4.0, 8.0}) {
    for (uint64_t seed = 11; seed < 16; ++seed) {
      const DPPair p = TexturedPatch(psf, radius, seed, seed + 100, 0.01);
      const PatchBlurEstimate e = estimator.Estimate(p.left, p.right);
      ++tried;
      if (e.evidence != BlurEvidence::kMeasured) continue;
      ++measured;
      EXPECT_TRUE(e.valid);
      EXPECT_TRUE(std::isfinite(e.radius_se_px));
      // A measured radius holds the truth within its own 4 sigma (and 0.3
      // px: the in-focus plateau of the disk reads as 0 up to 0.5 px).
      EXPECT_LE(std::abs(e.radius_px - radius),
                std::max(4 * e.radius_se_px, 0.3))
          << "r = " << radius << " seed " << seed << " read " << e.radius_px
          << " +- " << e.radius_se_px;
    }
  }
  EXPECT_GE(measured, 0.9 * tried);
}

// Blur rendered past the bound: beyond the bound, never measured.
TEST(BlurEvidence, BlurPastTheBoundIsBeyondIt) {
  const TranslatingDiskPsf psf;
  BlurEstimationOptions options = Options();
  options.max_radius_px = 6;
  const PatchBlurEstimator estimator(
      psf, options, cv::Size(Crop(psf), Crop(psf)));
  int beyond = 0, tried = 0;
  for (const double radius : {-9.5, 9.0}) {
    for (uint64_t seed = 21; seed < 26; ++seed) {
      const DPPair p = TexturedPatch(psf, radius, seed, seed + 100, 0.005);
      const PatchBlurEstimate e = estimator.Estimate(p.left, p.right);
      ++tried;
      EXPECT_NE(e.evidence, BlurEvidence::kMeasured)
          << "r = " << radius << " read " << e.radius_px;
      EXPECT_FALSE(e.valid);
      beyond += e.evidence == BlurEvidence::kBeyondBound;
      if (e.evidence == BlurEvidence::kBeyondBound) {
        EXPECT_TRUE(e.at_bound);
        EXPECT_EQ(e.reject_reason, kBlurAtSearchBound);
        EXPECT_GT(e.radius_px * radius, 0) << "the bound on the right side";
      }
    }
  }
  EXPECT_GE(beyond, 0.8 * tried);
}

// A patch across a depth edge (half at one blur, half at another) is never
// a confident wrong radius: undetermined, or measured with an interval that
// reaches the blurs present.
TEST(BlurEvidence, DepthEdgeIsNeverConfidentlyWrong) {
  const TranslatingDiskPsf psf;
  const PatchBlurEstimator estimator(
      psf, Options(), cv::Size(Crop(psf), Crop(psf)));
  int tried = 0, measured = 0;
  for (const auto& pair : std::vector<std::pair<double, double>>{
           {1.0, 7.0}, {-4.0, 4.0}, {-7.0, -2.0}, {2.0, 9.0}}) {
    for (uint64_t seed = 31; seed < 36; ++seed) {
      const DPPair p =
          TexturedPatch(psf, pair.first, seed, seed + 100, 0.005, pair.second);
      const PatchBlurEstimate e = estimator.Estimate(p.left, p.right);
      ++tried;
      if (e.evidence != BlurEvidence::kMeasured) continue;
      ++measured;
      const double lo = std::min(pair.first, pair.second);
      const double hi = std::max(pair.first, pair.second);
      const double reach = 1.96 * e.radius_se_px + 0.25;
      EXPECT_TRUE(e.radius_px + reach >= lo && e.radius_px - reach <= hi)
          << "blurs " << pair.first << " and " << pair.second << " seed "
          << seed << " read " << e.radius_px << " +- " << e.radius_se_px;
    }
  }
  std::printf("depth edges: %d of %d measured\n", measured, tried);
}

// The standard error from the curve against the spread of r over noise
// draws of the same patch: within a factor 1.5.
TEST(BlurEvidence, StandardErrorMatchesTheSpreadOverNoise) {
  const TranslatingDiskPsf psf;
  const PatchBlurEstimator estimator(
      psf, Options(), cv::Size(Crop(psf), Crop(psf)));
  for (const double radius : {-5.0, 3.0, 7.0}) {
    for (const double noise : {0.01, 0.03}) {
      std::vector<double> radii, errors;
      for (uint64_t seed = 1; seed <= 60; ++seed) {
        const DPPair p = TexturedPatch(psf, radius, 41, 1000 + seed, noise);
        const PatchBlurEstimate e = estimator.Estimate(p.left, p.right);
        if (e.evidence != BlurEvidence::kMeasured) continue;
        radii.push_back(e.radius_px);
        errors.push_back(e.radius_se_px);
      }
      ASSERT_GE(radii.size(), 40u) << "r = " << radius << " noise " << noise;
      double mean = 0;
      for (double r : radii) mean += r / radii.size();
      double var = 0;
      for (double r : radii)
        var += (r - mean) * (r - mean) / (radii.size() - 1);
      const double spread = std::sqrt(var);
      const double se = Median(errors);
      std::printf(
          "r = %+.1f noise %.2f: spread %.4f px, standard error %.4f px "
          "(%zu measured)\n",
          radius,
          noise,
          spread,
          se,
          radii.size());
      EXPECT_LE(se, 1.5 * spread) << "r = " << radius << " noise " << noise;
      EXPECT_GE(se, spread / 1.5) << "r = " << radius << " noise " << noise;
    }
  }
}

}  // namespace
}  // namespace dpsfm
