// Patch selection: the top-T_c share by confidence, and its spread over
// depth, against hand-made rankings.
#include "dpsfm/core/blur/patch_selection.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "dpsfm/core/blur/blur_estimation.h"
#include "dpsfm/core/blur/patch_grid.h"

namespace dpsfm {
namespace {

TEST(SelectTopFraction, KeepsBestTenPercentWithMinimum) {
  std::vector<double> conf(50);
  for (int i = 0; i < 50; ++i) conf[i] = (i * 37) % 50;
  const std::vector<int> top = SelectTopFraction(conf, 0.1, 3);
  ASSERT_EQ(top.size(), 5u);
  for (int i : top) EXPECT_GE(conf[i], 45);
  EXPECT_EQ(SelectTopFraction(conf, 0.01, 4).size(), 4u);
  conf[7] = NAN;
  for (int i : SelectTopFraction(conf, 0.98, 0)) EXPECT_NE(i, 7);
  EXPECT_TRUE(SelectTopFraction({}, 0.1, 3).empty());
}

TEST(SelectTopFractionStratified, SpreadsOverDepth) {
  // 90 patches on three planes; the nearest plane is the most textured, so a
  // plain top 10 % takes only it.
  std::vector<double> conf, key;
  for (int i = 0; i < 90; ++i) {
    const int plane = i % 3;
    key.push_back(1.0 / (1.0 + plane));
    conf.push_back((plane == 0 ? 100 : 10) + i * 0.01);
  }
  std::vector<int> plain = SelectTopFraction(conf, 0.1, 0);
  for (int i : plain) EXPECT_EQ(i % 3, 0);
  const std::vector<int> spread =
      SelectTopFractionStratified(conf, key, 0.1, 0, 4);
  ASSERT_EQ(spread.size(), plain.size());
  int per_plane[3] = {0, 0, 0};
  for (int i : spread) per_plane[i % 3]++;
  for (int p = 0; p < 3; ++p) EXPECT_EQ(per_plane[p], 3) << p;
  // strata = 1 is the plain selection.
  EXPECT_EQ(SelectTopFractionStratified(conf, key, 0.1, 0, 1), plain);
}

TEST(PatchConfidence, TextureTimesFitOverFlooredDepthVariance) {
  // 2 x 0.5 / (0.0099 + 1e-4) = 100; the 1e-4 floor (1 % depth std) rules
  // for a perfectly flat patch: 3 x 1 / 1e-4 = 30000.
  EXPECT_NEAR(PatchConfidence(2.0, 0.5, 0.0099), 100.0, 1e-9);
  EXPECT_NEAR(PatchConfidence(3.0, 1.0, 0.0), 30000.0, 1e-6);
  // Negative texture or fit quality count as nothing.
  EXPECT_EQ(PatchConfidence(-1.0, 0.5, 0.01), 0.0);
  EXPECT_EQ(PatchConfidence(1.0, -0.5, 0.01), 0.0);
}

// The noise bound screening settles most patches with is an upper bound of
// the noise, and the screening's decisions are those of the full noise
// estimate: views whose texture and noise vary over the frame (so both
// sides of the threshold occur), every decision checked against
// TextureSnr(Texture, NoiseSigma) by PatchScreening itself.
TEST(ScreenPatches, TheNoiseBoundDecidesAsTheNoiseWould) {
  std::mt19937 rng(11);
  std::normal_distribution<float> noise(0, 1);
  cv::Mat scene(240, 320, CV_32FC1);
  cv::randu(scene, 0, 1);
  cv::GaussianBlur(scene, scene, cv::Size(0, 0), 3);
  cv::Mat left(scene.size(), CV_32FC1), right(scene.size(), CV_32FC1);
  for (int y = 0; y < scene.rows; ++y) {
    for (int x = 0; x < scene.cols; ++x) {
      // Texture fading to the right, noise growing downwards.
      const float texture = 1.0f - x / 320.0f;
      const float sigma = 0.002f + 0.02f * y / 240.0f;
      const float v = 0.5f + texture * (scene.at<float>(y, x) - 0.5f);
      left.at<float>(y, x) = v + sigma * noise(rng);
      right.at<float>(y, x) = v + sigma * noise(rng) + (y % 7 == 0 ? 0.01f : 0);
    }
  }
  const int border = 6;
  const std::vector<PatchCandidate> candidates =
      MakePatchGrid(left.size(), 16, 8, border);
  const PatchScreening screening(left, right);
  // Thresholds at the quartiles of the patches' SNR.
  std::vector<double> snr;
  for (const PatchCandidate& c : candidates) {
    const cv::Rect r = PatchCrop(c.interior, border);
    snr.push_back(screening.TextureSnr(r));
  }
  std::sort(snr.begin(), snr.end());
  for (const double quantile : {0.25, 0.5, 0.75}) {
    const double min_snr = snr[quantile * snr.size()] / 0.9;
    std::vector<PatchBlurEstimate> estimates(candidates.size());
    const ScreenedPatches screened =
        ScreenPatches(left, right, candidates, border, min_snr, 2, &estimates);
    std::vector<char> passed(candidates.size(), 0);
    for (const int k : screened.index) passed[k] = 1;
    int num_passed = 0, num_failed = 0;
    for (size_t k = 0; k < candidates.size(); ++k) {
      const cv::Rect r = PatchCrop(candidates[k].interior, border);
      const double sigma = screening.NoiseSigma(r);
      EXPECT_LE(sigma, screening.NoiseSigmaBound(r)) << k;
      const bool passes =
          TextureSnr(screening.Texture(r), sigma) >= 0.9 * min_snr;
      EXPECT_EQ(passed[k], passes) << "min SNR " << min_snr << ", patch " << k;
      if (!passes) {
        EXPECT_EQ(estimates[k].reject_reason, kTextureTooWeak);
        EXPECT_EQ(estimates[k].noise_sigma, sigma);
      }
      (passes ? num_passed : num_failed)++;
    }
    EXPECT_GT(num_passed, 0) << min_snr;
    EXPECT_GT(num_failed, 0) << min_snr;
  }
}

}  // namespace
}  // namespace dpsfm
