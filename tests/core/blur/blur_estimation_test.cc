#include "dpsfm/core/blur/blur_estimation.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>

#include <gtest/gtest.h>

#include "tests/core/synthetic_dp.h"

namespace dpsfm {
namespace {

using test::DPPair;
using test::MakeTexture;
using test::RenderDP;
using test::RenderOptions;

constexpr int kPatch = 111;

// A textured DP patch of kPatch pixels at blur r: rendered on a larger canvas
// (so the patch border holds real blurred content) and cropped.
DPPair MakePatch(double radius,
                 uint64_t seed,
                 double noise_sigma,
                 double left_gain = 1,
                 double right_gain = 1,
                 int patch = kPatch) {
  const TranslatingDiskPsf psf;
  const int margin = 32;
  // Natural scenes carry most contrast at low frequencies (and edges), which
  // is what survives heavy blur; the texture has both.
  test::TextureOptions texture;
  texture.coarsest_cell_px = 48;
  texture.octaves = 6;
  texture.shapes_per_10k_px = 6;
  const cv::Mat sharp = MakeTexture(
      cv::Size(patch + 2 * margin, patch + 2 * margin), seed, texture);
  RenderOptions render;
  render.noise_sigma = noise_sigma;
  render.noise_seed = seed + 1000;
  render.left_gain = left_gain;
  render.right_gain = right_gain;
  const DPPair full = RenderDP(sharp, psf, radius, render);
  const cv::Rect crop(margin, margin, patch, patch);
  return DPPair{full.left(crop).clone(), full.right(crop).clone()};
}

TEST(BlurEstimationOptions, Check) {
  BlurEstimationOptions options;
  EXPECT_TRUE(options.Check());
  options.coarse_step_px = 0.3;  // not a multiple of the grid step
  EXPECT_FALSE(options.Check());
  options = BlurEstimationOptions();
  options.max_radius_px = 0;
  EXPECT_FALSE(options.Check());
  options = BlurEstimationOptions();
  options.min_fit_quality = 2;
  EXPECT_FALSE(options.Check());
}

TEST(EstimatePatchBlur, RecoversSignedBlurWithNoise) {
  const TranslatingDiskPsf psf;
  const BlurEstimationOptions options;
  const PatchBlurEstimator estimator(psf, options, cv::Size(kPatch, kPatch));
  double worst = 0;
  int seed = 1;
  for (const double magnitude : {1.0, 1.3, 2.0, 3.6, 5.0, 7.75, 10.2, 15.0}) {
    for (const double sign : {-1.0, 1.0}) {
      const double radius = sign * magnitude;
      const DPPair pair = MakePatch(radius, seed++, 0.01);
      const PatchBlurEstimate estimate =
          estimator.Estimate(pair.left, pair.right);
      EXPECT_TRUE(estimate.valid)
          << "r = " << radius << ": " << estimate.reject_reason;
      EXPECT_NEAR(estimate.radius_px, radius, 0.1) << "r = " << radius;
      EXPECT_GT(estimate.radius_px * radius, 0) << "wrong sign at " << radius;
      // Within ~1 px of focus the loss rises little towards the in-focus
      // plateau, so the confidence is lower there.
      EXPECT_GT(estimate.fit_quality, magnitude < 2 ? 0.15 : 0.4)
          << "r = " << radius;
      EXPECT_NEAR(estimate.noise_sigma, 0.01, 0.003) << "r = " << radius;
      worst = std::max(worst, std::abs(estimate.radius_px - radius));
    }
  }
  std::printf("worst |error| over the sweep: %.4f px\n", worst);
}

TEST(EstimatePatchBlur, InFocusReadsNearZero) {
  const TranslatingDiskPsf psf;
  const BlurEstimationOptions options;
  for (int seed = 50; seed < 54; ++seed) {
    for (const double radius : {0.0, 0.3}) {
      const DPPair pair = MakePatch(radius, seed, 0.01);
      const PatchBlurEstimate estimate =
          EstimatePatchBlur(pair.left, pair.right, psf, options);
      EXPECT_TRUE(estimate.valid) << estimate.reject_reason;
      EXPECT_LT(std::abs(estimate.radius_px), 0.5)
          << "seed " << seed << " r = " << radius;
    }
  }
}

TEST(EstimatePatchBlur, NoiseDoesNotInflateSmallBlurs) {
  // The noise bias (docs/method.md, "Blur search"): noise adds
  // sigma^2 (|H_l|^2 + |H_r|^2) to the loss, most for the sharpest kernels,
  // so without the noise-floor correction small blurs read large. With it,
  // the estimate stays put.
  const TranslatingDiskPsf psf;
  BlurEstimationOptions options;
  options.max_radius_px = 10;
  const PatchBlurEstimator corrected(psf, options, cv::Size(61, 61));
  options.subtract_noise_floor = false;
  const PatchBlurEstimator uncorrected(psf, options, cv::Size(61, 61));
  double bias_corrected = 0, bias_uncorrected = 0;
  int count = 0;
  for (int seed = 70; seed < 76; ++seed) {
    for (const double radius : {-1.5, 1.5, 2.0}) {
      const DPPair pair = MakePatch(radius, seed, 0.015, 1, 1, 61);
      bias_corrected +=
          std::abs(corrected.Estimate(pair.left, pair.right).radius_px) -
          std::abs(radius);
      bias_uncorrected +=
          std::abs(uncorrected.Estimate(pair.left, pair.right).radius_px) -
          std::abs(radius);
      ++count;
    }
  }
  bias_corrected /= count;
  bias_uncorrected /= count;
  std::printf(
      "mean |r| bias at sigma 0.015: corrected %.3f, uncorrected %.3f\n",
      bias_corrected,
      bias_uncorrected);
  EXPECT_LT(std::abs(bias_corrected), 0.1);
  EXPECT_GT(bias_uncorrected, 0.3);  // the effect is real
}

TEST(EstimatePatchBlur, GainDifferenceIsEqualised) {
  const TranslatingDiskPsf psf;
  const BlurEstimationOptions options;
  const DPPair pair = MakePatch(-3.0, 91, 0.005, 1.15, 0.85);
  const PatchBlurEstimate estimate =
      EstimatePatchBlur(pair.left, pair.right, psf, options);
  EXPECT_TRUE(estimate.valid);
  EXPECT_NEAR(estimate.radius_px, -3.0, 0.1);
}

TEST(EstimatePatchBlur, FlatPatchIsRejectedOrUnconfident) {
  const TranslatingDiskPsf psf;
  const BlurEstimationOptions options;
  // Exactly flat: rejected outright.
  const cv::Mat flat(kPatch, kPatch, CV_32FC1, cv::Scalar(0.4));
  PatchBlurEstimate estimate = EstimatePatchBlur(flat, flat, psf, options);
  EXPECT_FALSE(estimate.valid);
  EXPECT_FALSE(estimate.reject_reason.empty());
  // Flat plus noise: no usable confidence.
  const auto flat_with_noise = [&](uint64_t seed) {
    DPPair pair;
    pair.left = flat.clone();
    pair.right = flat.clone();
    RenderOptions render;
    render.noise_sigma = 0.01;
    render.noise_seed = seed;
    test::internal::FinishViews(render, &pair);
    return EstimatePatchBlur(pair.left, pair.right, psf, options);
  };
  // Flat plus noise: no blur the loss curve determines, whatever the noise
  // draws (before the curve's evidence was weighed, draws 2-7 read as |r|
  // of 11-17 px and came back valid).
  for (uint64_t seed = 1; seed < 8; ++seed) {
    const PatchBlurEstimate other = flat_with_noise(seed);
    EXPECT_FALSE(other.valid)
        << "noise seed " << seed << ": r = " << other.radius_px;
    EXPECT_NE(other.evidence, BlurEvidence::kMeasured);
    EXPECT_LT(other.fit_quality, 0.2)
        << "noise seed " << seed << ": r = " << other.radius_px;
  }
  estimate = flat_with_noise(1);
  // A textured patch at the same noise is confident.
  const DPPair textured = MakePatch(4.0, 93, 0.01);
  const PatchBlurEstimate good =
      EstimatePatchBlur(textured.left, textured.right, psf, options);
  EXPECT_GT(good.fit_quality, 0.5);
  EXPECT_GT(good.texture, 2 * estimate.texture);
  EXPECT_GT(good.fit_quality, 3 * estimate.fit_quality);
}

TEST(EstimatePatchBlur, BeyondTheBoundIsRejected) {
  const TranslatingDiskPsf psf;
  BlurEstimationOptions options;
  options.max_radius_px = 10;
  for (const double radius : {14.0, -13.0}) {
    const DPPair pair = MakePatch(radius, 97, 0.005, 1, 1, 61);
    const PatchBlurEstimate estimate =
        EstimatePatchBlur(pair.left, pair.right, psf, options);
    EXPECT_FALSE(estimate.valid)
        << "r = " << radius << " read as " << estimate.radius_px;
    EXPECT_TRUE(estimate.at_bound) << "r = " << radius;
  }
}

// A patch blurred far beyond the search bound (the near floor of a tabletop
// scene at r = -20..-30 px against an automatic bound of 5.5 px) fits no
// kernel pair, yet its loss can have an interior minimum at a small radius:
// it used to come back as a valid "nearly in focus" patch. It must be
// rejected or flagged by its relative residual, which stays tiny for patches
// inside the bound.
TEST(EstimatePatchBlur, FarBeyondTheBoundIsNotAFit) {
  const TranslatingDiskPsf psf;
  BlurEstimationOptions options;
  options.max_radius_px = 5.5;
  const int patch = 33 + 2 * psf.KernelRadius(5.5);  // the pipeline's crop
  double worst_inside = 0;
  for (const double radius : {2.0, -3.5, 4.5}) {
    for (uint64_t seed = 201; seed < 205; ++seed) {
      const DPPair pair = MakePatch(radius, seed, 0.002, 1, 1, patch);
      const PatchBlurEstimate e =
          EstimatePatchBlur(pair.left, pair.right, psf, options);
      ASSERT_TRUE(e.valid) << "r = " << radius << ": " << e.reject_reason;
      EXPECT_NEAR(e.radius_px, radius, 0.35);
      worst_inside = std::max(worst_inside, e.relative_residual);
    }
  }
  EXPECT_LT(worst_inside, 0.001);
  // Smooth multi-octave texture (value noise with cells of 160 px down to
  // 5 px, as the example scene's surfaces at 0.5 m):
  // heavy blur leaves little structure and spurious interior minima appear.
  test::TextureOptions smooth;
  smooth.coarsest_cell_px = 160;
  smooth.octaves = 6;
  smooth.persistence = 0.75;
  smooth.shapes_per_10k_px = 0;
  int valid_beyond = 0, tried = 0;
  for (const double radius : {-24.0, -16.0, 18.0}) {
    for (uint64_t seed = 211; seed < 231; ++seed) {
      const int margin = 64;
      const cv::Mat sharp = MakeTexture(
          cv::Size(patch + 2 * margin, patch + 2 * margin), seed, smooth);
      RenderOptions render;
      render.noise_sigma = 0.002;
      render.noise_seed = seed + 1000;
      const DPPair full = RenderDP(sharp, psf, radius, render);
      const cv::Rect crop(margin, margin, patch, patch);
      const DPPair pair{full.left(crop).clone(), full.right(crop).clone()};
      ++tried;
      const PatchBlurEstimate e =
          EstimatePatchBlur(pair.left, pair.right, psf, options);
      valid_beyond += e.valid;
      // Rejected as beyond the bound or as undetermined; and flagged by the
      // relative residual whether or not the evidence caught it.
      if (!e.valid) {
        EXPECT_TRUE(e.reject_reason == kBlurAtSearchBound ||
                    e.reject_reason == kBlurUndetermined)
            << "r = " << radius << ": " << e.reject_reason;
        if (e.evidence == BlurEvidence::kBeyondBound) {
          EXPECT_TRUE(e.at_bound) << "r = " << radius;
        }
      }
      EXPECT_GT(e.relative_residual, 3 * worst_inside)
          << "r = " << radius << " seed " << seed << " read as " << e.radius_px
          << (e.valid ? " (valid)" : " (rejected)")
          << " with relative residual " << e.relative_residual
          << " (inside the bound <= " << worst_inside << ")";
    }
  }
  std::printf("far beyond the bound: %d of %d valid\n", valid_beyond, tried);
}

// A patch prepared once and searched with several profiles: the same
// estimate as the search from the crops, to the last bit, and the prepared
// patch unchanged by the searches (the gain equalisation works on copies).
TEST(PatchBlurEstimator, PreparedPatchSearchesLikeTheCrops) {
  const DPPair p = MakePatch(5.5, 31, 0.005, 1.0, 0.85);
  BlurEstimationOptions options;
  options.max_radius_px = 10;
  const TranslatingDiskPsf disk;
  const PatchBlurEstimator first(disk, options, p.left.size());
  const PreparedBlurPatch prepared = first.Prepare(p.left, p.right);
  ASSERT_TRUE(prepared.early.reject_reason.empty());
  const cv::Mat gl = prepared.gl.clone(), gr = prepared.gr.clone();
  for (const double kappa : {0.15, 0.283, 0.4}) {
    const SplitProfilePsf psf(SplitProfileParams::ForCentroidOffset(kappa));
    const PatchBlurEstimator estimator(psf, options, p.left.size());
    const PatchBlurEstimate a = estimator.Estimate(p.left, p.right);
    const PatchBlurEstimate b = estimator.Estimate(prepared);
    EXPECT_EQ(a.valid, b.valid) << kappa;
    EXPECT_EQ(a.radius_px, b.radius_px) << kappa;
    EXPECT_EQ(a.corrected_loss, b.corrected_loss) << kappa;
    EXPECT_EQ(a.fit_quality, b.fit_quality) << kappa;
    EXPECT_EQ(a.relative_residual, b.relative_residual) << kappa;
    EXPECT_EQ(a.noise_sigma, b.noise_sigma) << kappa;
    EXPECT_GT(std::abs(a.radius_px), 1) << kappa;
    EXPECT_EQ(cv::norm(prepared.gl, gl, cv::NORM_INF), 0) << kappa;
    EXPECT_EQ(cv::norm(prepared.gr, gr, cv::NORM_INF), 0) << kappa;
  }
  // Prepared for another crop size: refused.
  const DPPair small = MakePatch(2, 32, 0.005, 1, 1, 81);
  const PreparedBlurPatch other =
      PatchBlurEstimator(disk, options, small.left.size())
          .Prepare(small.left, small.right);
  EXPECT_THROW(first.Estimate(other), std::exception);
  // A flat patch ends in the preparation, with its reason.
  const cv::Mat flat(p.left.size(), CV_32FC1, cv::Scalar(0.5));
  const PreparedBlurPatch none = first.Prepare(flat, flat);
  EXPECT_EQ(first.Estimate(none).reject_reason, "no horizontal texture");
}

TEST(EstimatePatchBlur, RejectsBadInput) {
  const TranslatingDiskPsf psf;
  const BlurEstimationOptions options;
  const cv::Mat small(31, 31, CV_32FC1, cv::Scalar(0.5));
  EXPECT_THROW(EstimatePatchBlur(small, small, psf, options),
               std::invalid_argument);
  const cv::Mat a(kPatch, kPatch, CV_32FC1, cv::Scalar(0.5));
  const cv::Mat b(kPatch, kPatch + 2, CV_32FC1, cv::Scalar(0.5));
  EXPECT_THROW(EstimatePatchBlur(a, b, psf, options), std::invalid_argument);
  DPPair pair = MakePatch(2.0, 5, 0);
  EXPECT_TRUE(EstimatePatchBlur(pair.left, pair.right, psf, options).valid);
  pair.left.at<float>(50, 50) = std::nanf("");
  const PatchBlurEstimate estimate =
      EstimatePatchBlur(pair.left, pair.right, psf, options);
  EXPECT_FALSE(estimate.valid);
  EXPECT_NE(estimate.reject_reason.find("non-finite"), std::string::npos)
      << estimate.reject_reason;
}

TEST(PatchGeometry, Defaults) {
  // The reference code's DSLR anchor, at its explicit resize.
  const PatchGeometry dslr = DefaultPatchGeometry(cv::Size(6720, 4480), 0.5);
  EXPECT_DOUBLE_EQ(dslr.resize_factor, 0.5);
  EXPECT_EQ(dslr.patch_size, 111);
  EXPECT_EQ(dslr.stride, 47);
  EXPECT_DOUBLE_EQ(dslr.max_radius_px, 20);
  // Automatically the same 40 frame px of bound at 1/4, where it is 10.
  const PatchGeometry dslr_auto = DefaultPatchGeometry(cv::Size(6720, 4480));
  EXPECT_DOUBLE_EQ(dslr_auto.resize_factor, 0.25);
  EXPECT_DOUBLE_EQ(dslr_auto.max_radius_px, 10);
  EXPECT_EQ(dslr_auto.patch_size, 51);
  const PatchGeometry phone = DefaultPatchGeometry(cv::Size(2016, 1512));
  EXPECT_DOUBLE_EQ(phone.resize_factor, 1.0);
  EXPECT_EQ(phone.patch_size, 51);
  EXPECT_EQ(phone.stride, 27);
  EXPECT_DOUBLE_EQ(phone.max_radius_px, 10);
  // 3000x2000: 16.5 frame px of bound (as at full resolution), halved.
  const PatchGeometry full = DefaultPatchGeometry(cv::Size(3000, 2000), 1.0);
  EXPECT_DOUBLE_EQ(full.max_radius_px, 16.5);
  const PatchGeometry half = DefaultPatchGeometry(cv::Size(3000, 2000));
  EXPECT_DOUBLE_EQ(half.resize_factor, 0.5);
  EXPECT_DOUBLE_EQ(half.max_radius_px, 8.5);  // 8.25 on the half-px grid
  // Below ~1880 px on the short side nothing is resized.
  EXPECT_DOUBLE_EQ(DefaultPatchGeometry(cv::Size(2700, 1800)).resize_factor,
                   1.0);
  EXPECT_DOUBLE_EQ(DefaultPatchGeometry(cv::Size(1000, 667)).resize_factor,
                   1.0);
  // The rule on its own reproduces both anchors (a calibrated profile's
  // bound for small frames uses it).
  const PatchGeometry ten = PatchGeometryForRadius(10, 1.0);
  EXPECT_EQ(ten.patch_size, 51);
  EXPECT_EQ(ten.stride, 27);
  const PatchGeometry twenty = PatchGeometryForRadius(20, 0.5);
  EXPECT_EQ(twenty.patch_size, 111);
  EXPECT_EQ(twenty.stride, 47);
  EXPECT_DOUBLE_EQ(twenty.resize_factor, 0.5);
  // In between: odd, and the bound fits the patch; the working bound stays
  // within a factor 1.5 of 10 px once frames are reduced.
  const PatchGeometry mid = DefaultPatchGeometry(cv::Size(3000, 2000), 1.0);
  EXPECT_EQ(mid.patch_size % 2, 1);
  EXPECT_GT(mid.patch_size, 51);
  EXPECT_LT(mid.patch_size, 111);
  for (const int side : {2000, 2240, 2800, 3500, 4000, 4480, 6000}) {
    const PatchGeometry g = DefaultPatchGeometry(cv::Size(side * 3 / 2, side));
    EXPECT_LT(g.resize_factor, 1.0) << side;
    EXPECT_GE(g.max_radius_px, 6.5) << side;
    EXPECT_LE(g.max_radius_px, 13.5) << side;
  }
  for (const int side : {300, 800, 1512, 2000, 2240, 2800, 3500}) {
    const PatchGeometry g = DefaultPatchGeometry(cv::Size(side * 3 / 2, side));
    EXPECT_EQ(g.patch_size % 2, 1);
    EXPECT_GE(g.patch_size, 2 * g.max_radius_px + 21) << side;
    EXPECT_GT(g.stride, 0);
  }
  EXPECT_THROW(DefaultPatchGeometry(cv::Size(0, 10)), std::invalid_argument);
}

TEST(HorizontalTexture, SeesOnlyVerticalEdges) {
  cv::Mat vertical_edge = cv::Mat::zeros(20, 20, CV_32FC1);
  vertical_edge(cv::Rect(10, 0, 10, 20)).setTo(1);
  cv::Mat horizontal_edge = vertical_edge.t();
  EXPECT_GT(HorizontalTexture(vertical_edge), 0.3);
  EXPECT_EQ(HorizontalTexture(horizontal_edge), 0.0);
}

TEST(EstimateNoiseSigma, MatchesGaussianNoise) {
  cv::Mat noise(200, 200, CV_32FC1);
  cv::RNG rng(3);
  rng.fill(noise, cv::RNG::NORMAL, 0.5, 0.02);
  EXPECT_NEAR(EstimateNoiseSigma(noise), 0.02, 0.001);
}

// NoiseSigmaReaches(p, sigma) is EstimateNoiseSigma(p) >= sigma, exactly:
// at the estimate itself, at the next double on either side (where a
// threshold off by one rounding step would tell), and at random sigmas, on
// patches of either parity of response count, with texture and without.
TEST(NoiseSigmaReaches, TheEstimateComparedToTheBit) {
  cv::RNG rng(5);
  for (const cv::Size size : {cv::Size(23, 19), cv::Size(24, 24)}) {
    for (const double texture : {0.0, 0.2}) {
      cv::Mat patch(size, CV_32FC1);
      rng.fill(patch, cv::RNG::NORMAL, 0.5, 0.01);
      for (int y = 0; y < size.height; ++y) {
        for (int x = 0; x < size.width; ++x) {
          patch.at<float>(y, x) += texture * std::sin(0.7 * x + 0.3 * y);
        }
      }
      const double sigma = EstimateNoiseSigma(patch);
      ASSERT_GT(sigma, 0);
      EXPECT_TRUE(NoiseSigmaReaches(patch, sigma));
      EXPECT_TRUE(NoiseSigmaReaches(patch, std::nextafter(sigma, 0.0)));
      EXPECT_FALSE(NoiseSigmaReaches(patch, std::nextafter(sigma, 1.0)));
      for (int k = 0; k < 200; ++k) {
        const double s = sigma * rng.uniform(0.5, 1.5);
        EXPECT_EQ(NoiseSigmaReaches(patch, s), sigma >= s) << s;
      }
      EXPECT_FALSE(NoiseSigmaReaches(patch, std::nan("")));
    }
  }
}

// PairNoiseVariance is the smaller of the views' variance and the
// difference's, as the three full estimates give it, to the bit: with views
// that differ by noise only (the difference's wins: the shortcut that skips
// the views' medians) and with views that differ by a pattern (the views'
// wins: their medians, from the responses the count used).
TEST(PairNoiseVariance, TheSmallerOfTheThreeEstimatesToTheBit) {
  cv::RNG rng(9);
  int differences = 0, views = 0;
  for (int trial = 0; trial < 12; ++trial) {
    const cv::Size size(31 + trial % 2, 27);
    cv::Mat left(size, CV_32FC1), right(size, CV_32FC1), noise(size, CV_32FC1);
    rng.fill(left, cv::RNG::NORMAL, 0.0, 0.01);
    for (int y = 0; y < size.height; ++y) {
      for (int x = 0; x < size.width; ++x) {
        left.at<float>(y, x) += 0.2f * std::sin(0.7 * x + 0.3 * y);
      }
    }
    rng.fill(noise, cv::RNG::NORMAL, 0.0, 0.002 * (1 + trial % 3));
    right = left + noise;
    if (trial >= 6) {
      // A pattern in one view only: it inflates the difference's estimate.
      for (int y = 0; y < size.height; ++y) {
        for (int x = 0; x < size.width; ++x) {
          right.at<float>(y, x) += ((x + y) % 2 ? 0.05f : -0.05f);
        }
      }
    }
    const double sl = EstimateNoiseSigma(left);
    const double sr = EstimateNoiseSigma(right);
    const double sd =
        EstimateNoiseSigma(cv::Mat(left - right)) / std::sqrt(2.0);
    const double views_variance = 0.5 * (sl * sl + sr * sr);
    const double expected = std::min(views_variance, sd * sd);
    EXPECT_EQ(PairNoiseVariance(left, right), expected) << "trial " << trial;
    (views_variance < sd * sd ? views : differences) += 1;
  }
  EXPECT_GT(differences, 0);
  EXPECT_GT(views, 0);
}

}  // namespace
}  // namespace dpsfm
