#include "dpsfm/core/psf_calibration.h"

#include <cmath>
#include <cstdio>
#include <vector>

#include <gtest/gtest.h>

#include "synthetic_dp.h"

namespace dpsfm {
namespace {

constexpr int kCrop = 97;
constexpr double kMaxRadius = 14;

// Textured patches rendered with `psf` at radii from +-2.5 to 12 px.
std::vector<ProfilePatch> RenderPatches(
    const DPPsfModel& psf, int count, double noise, bool known, int seed) {
  const double radii[] = {-9, -6, -4, -2.5, 2.5, 4, 6, 9, 12};
  std::vector<ProfilePatch> patches;
  for (int k = 0; k < count; ++k) {
    test::TextureOptions texture;
    const cv::Mat sharp =
        test::MakeTexture(cv::Size(kCrop, kCrop), seed + k, texture);
    const double r = radii[k % 9];
    test::RenderOptions render;
    render.noise_sigma = noise;
    render.noise_seed = 3 * seed + k;
    const test::DPPair pair = test::RenderDP(sharp, psf, r, render);
    ProfilePatch patch;
    patch.left = test::ToGray(pair.left);
    patch.right = test::ToGray(pair.right);
    if (known) patch.known_radius_px = r;
    patches.push_back(patch);
  }
  return patches;
}

SplitProfileFitOptions FastOptions() {
  SplitProfileFitOptions options;
  options.blur.max_radius_px = kMaxRadius;
  options.num_grid = 9;
  options.num_refine = 4;
  options.num_bootstrap = 100;
  return options;
}

double Centroid(double exponent) {
  SplitProfileParams params;
  params.split_exponent = exponent;
  return CentroidOffsetPerRadius(SplitProfilePsf(params), 8);
}

void Print(const char* label, const SplitProfileFit& fit) {
  std::printf("%s: %s; %.1f s\n", label, fit.reason.c_str(), fit.seconds);
}

// Self-calibration recovers a sharper-than-disk split from the data alone:
// the centroid offset (what sets every radius, hence the scale) within 3 %.
TEST(FitSplitProfile, SelfCalibrationRecoversASharperSplit) {
  SplitProfileParams truth;
  truth.split_exponent = 0.35;
  const SplitProfilePsf psf(truth);
  const SplitProfileFit fit =
      FitSplitProfile(RenderPatches(psf, 36, 0.005, false, 11), FastOptions());
  Print("sharper split", fit);
  ASSERT_TRUE(fit.determined) << fit.reason;
  EXPECT_TRUE(fit.self_calibrated);
  EXPECT_FALSE(fit.translating_disk);
  EXPECT_NEAR(fit.centroid_offset / Centroid(0.35), 1.0, 0.03);
  EXPECT_LE(fit.exponent_ci_low, fit.params.split_exponent);
  EXPECT_GE(fit.exponent_ci_high, fit.params.split_exponent);
  EXPECT_GT(fit.centroid_offset, 1.15 * fit.translating_disk_centroid_offset);
}

// On translating-disk data it finds the translating disk.
TEST(FitSplitProfile, SelfCalibrationFindsTheTranslatingDisk) {
  const TranslatingDiskPsf psf;
  const SplitProfileFit fit =
      FitSplitProfile(RenderPatches(psf, 36, 0.005, false, 21), FastOptions());
  Print("translating disk", fit);
  ASSERT_TRUE(fit.determined) << fit.reason;
  EXPECT_TRUE(fit.translating_disk) << fit.reason;
  EXPECT_DOUBLE_EQ(fit.centroid_offset, fit.translating_disk_centroid_offset);
}

// Crosstalk is not in the fitted family; the fit still finds the profile
// whose radii come out right (within 4 %).
TEST(FitSplitProfile, SelfCalibrationAbsorbsCrosstalk) {
  SplitProfileParams truth;
  truth.crosstalk = 0.12;
  const SplitProfilePsf psf(truth);
  const std::vector<ProfilePatch> patches =
      RenderPatches(psf, 36, 0.005, false, 31);
  const SplitProfileFit fit = FitSplitProfile(patches, FastOptions());
  Print("crosstalk 0.12", fit);
  ASSERT_TRUE(fit.determined) << fit.reason;
  EXPECT_GT(fit.params.split_exponent, 1.2);
  // Radii recovered with the fitted profile against the truth.
  BlurEstimationOptions blur;
  blur.max_radius_px = kMaxRadius;
  const PatchBlurEstimator estimator(
      SplitProfilePsf(fit.params), blur, cv::Size(kCrop, kCrop));
  const double radii[] = {-9, -6, -4, -2.5, 2.5, 4, 6, 9, 12};
  std::vector<double> ratios;
  for (size_t k = 0; k < patches.size(); ++k) {
    const PatchBlurEstimate e =
        estimator.Estimate(patches[k].left, patches[k].right);
    if (e.valid && std::abs(radii[k % 9]) >= 4) {
      ratios.push_back(e.radius_px / radii[k % 9]);
    }
  }
  ASSERT_GT(ratios.size(), 20u);
  std::sort(ratios.begin(), ratios.end());
  EXPECT_NEAR(ratios[ratios.size() / 2], 1.0, 0.04);
}

// Known radii (a target at measured distances): the calibration recovers
// the exponent and reports the radius error.
TEST(FitSplitProfile, KnownRadiusCalibrationRoundTrip) {
  SplitProfileParams truth;
  truth.split_exponent = 2.0;
  const SplitProfilePsf psf(truth);
  const SplitProfileFit fit =
      FitSplitProfile(RenderPatches(psf, 36, 0.005, true, 41), FastOptions());
  Print("calibration, exponent 2", fit);
  ASSERT_TRUE(fit.determined) << fit.reason;
  EXPECT_FALSE(fit.self_calibrated);
  EXPECT_NEAR(fit.centroid_offset / Centroid(2.0), 1.0, 0.02);
  EXPECT_LT(fit.median_radius_error, 0.03);
}

// Nothing but near-focus patches: the profile cannot be seen, and the fit
// says so instead of guessing.
TEST(FitSplitProfile, SaysWhenTheDataCannotDetermineIt) {
  const TranslatingDiskPsf psf;
  std::vector<ProfilePatch> patches;
  for (int k = 0; k < 30; ++k) {
    test::TextureOptions texture;
    const cv::Mat sharp =
        test::MakeTexture(cv::Size(kCrop, kCrop), 300 + k, texture);
    const test::DPPair pair = test::RenderDP(sharp, psf, k % 2 ? 0.8 : -1.0);
    patches.push_back({test::ToGray(pair.left), test::ToGray(pair.right)});
  }
  const SplitProfileFit fit = FitSplitProfile(patches, FastOptions());
  Print("near focus", fit);
  EXPECT_FALSE(fit.determined);
  EXPECT_NE(fit.reason.find("2 px"), std::string::npos) << fit.reason;
  EXPECT_DOUBLE_EQ(fit.params.split_exponent, 1.0);
}

}  // namespace
}  // namespace dpsfm
