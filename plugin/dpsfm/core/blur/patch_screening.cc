// PatchScreening, HorizontalTexture, EstimateNoiseSigma, NoiseSigmaReaches,
// PairNoiseVariance and TextureSnr (declared in blur_estimation.h): the
// texture and noise measures that screen patches before the blur search and
// set its noise floor.
#include "dpsfm/core/blur/blur_estimation.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "dpsfm/core/util/check.h"
#include "dpsfm/core/util/statistics.h"

namespace dpsfm {

double HorizontalTexture(const cv::Mat& gray_patch) {
  DPSFM_CHECK(gray_patch.type() == CV_32FC1 && !gray_patch.empty())
      << "HorizontalTexture needs a non-empty CV_32FC1 patch";
  cv::Mat gx;
  cv::Sobel(gray_patch, gx, CV_32F, 1, 0, 3, 1, 0, cv::BORDER_REFLECT_101);
  return cv::mean(cv::abs(gx))[0];
}

namespace {

// The filter's gain: the norm of its taps.
constexpr double kNoiseMaskGain = 6.0;

// The mask's absolute responses over the patch without its outer ring.
std::vector<float> NoiseResponses(const cv::Mat& gray_patch) {
  DPSFM_CHECK(gray_patch.type() == CV_32FC1 && gray_patch.rows >= 3 &&
              gray_patch.cols >= 3)
      << "EstimateNoiseSigma needs a CV_32FC1 patch of at least 3x3";
  const int width = gray_patch.cols - 2;
  std::vector<float> responses(static_cast<size_t>(gray_patch.rows - 2) *
                               width);
  // Written by index rather than appended, so that the row loop vectorises.
  float* out = responses.data();
  for (int y = 1; y + 1 < gray_patch.rows; ++y, out += width) {
    const float* a = gray_patch.ptr<float>(y - 1);
    const float* b = gray_patch.ptr<float>(y);
    const float* c = gray_patch.ptr<float>(y + 1);
    for (int x = 1; x + 1 < gray_patch.cols; ++x) {
      const float v = (a[x - 1] - 2 * a[x] + a[x + 1]) -
                      2 * (b[x - 1] - 2 * b[x] + b[x + 1]) +
                      (c[x - 1] - 2 * c[x] + c[x + 1]);
      out[x - 1] = std::abs(v);
    }
  }
  return responses;
}

// The noise sigma behind the responses (consumed).
double SigmaOfResponses(std::vector<float>* responses) {
  return SigmaFromMedianAbsolute(UpperMedianBySelection(responses),
                                 kNoiseMaskGain);
}

// Whether SigmaOfResponses(responses) >= sigma, without selecting: the
// median absolute response t that gives sigma, rounded up to a float (a
// median >= t gives a sigma >= sigma, both steps monotone), and the value
// of rank n / 2 is >= t exactly when at most n / 2 values lie below t.
bool ResponsesReach(const std::vector<float>& responses, double sigma) {
  if (std::isnan(sigma)) return false;
  float t = static_cast<float>(sigma * kHalfNormalMedian * kNoiseMaskGain);
  while (SigmaFromMedianAbsolute(t, kNoiseMaskGain) < sigma) {
    t = std::nextafter(t, std::numeric_limits<float>::infinity());
  }
  size_t below = 0;
  for (const float v : responses) below += v < t;
  return below <= responses.size() / 2;
}

// The rule both noise estimates of a pair of views follow: the views'
// estimate (sl, sr) is inflated by texture, the difference's (its variance)
// by DP disparity; the smaller of the two variances.
double SmallerNoiseVariance(double sl, double sr, double difference_variance) {
  return std::min(0.5 * (sl * sl + sr * sr), difference_variance);
}

}  // namespace

double EstimateNoiseSigma(const cv::Mat& gray_patch) {
  std::vector<float> responses = NoiseResponses(gray_patch);
  return SigmaOfResponses(&responses);
}

bool NoiseSigmaReaches(const cv::Mat& gray_patch, double sigma) {
  return ResponsesReach(NoiseResponses(gray_patch), sigma);
}

double PairNoiseVariance(const cv::Mat& gl, const cv::Mat& gr) {
  cv::Mat diff = gl - gr;
  const double sd = EstimateNoiseSigma(diff) / std::sqrt(2.0);
  // Where both views' estimates reach sd, the smaller is the difference's
  // (0.5 (sl^2 + sr^2) >= sd^2, to the bit): their medians are not needed.
  // Each view is filtered once, for the count and, where it does not
  // settle it, the median.
  std::vector<float> left = NoiseResponses(gl);
  std::vector<float> right = NoiseResponses(gr);
  if (ResponsesReach(left, sd) && ResponsesReach(right, sd)) return sd * sd;
  return SmallerNoiseVariance(
      SigmaOfResponses(&left), SigmaOfResponses(&right), sd * sd);
}

namespace {

// EstimateNoiseSigma over `rect` (without its outer ring) from a map of
// absolute responses, on every other pixel in both directions: the median of
// thousands of responses is as good as that of all of them for screening.
double SubsampledNoiseSigma(const cv::Mat& response, const cv::Rect& rect) {
  std::vector<float> values;
  values.reserve((rect.width / 2 + 1) * (rect.height / 2 + 1));
  for (int y = rect.y + 1; y + 1 < rect.y + rect.height; y += 2) {
    const float* row = response.ptr<float>(y);
    for (int x = rect.x + 1; x + 1 < rect.x + rect.width; x += 2) {
      values.push_back(row[x]);
    }
  }
  if (values.empty()) return 0;
  return SigmaOfResponses(&values);
}

}  // namespace

PatchScreening::PatchScreening(const cv::Mat& gray_left,
                               const cv::Mat& gray_right) {
  DPSFM_CHECK(gray_left.type() == CV_32FC1 && gray_right.type() == CV_32FC1 &&
              gray_left.size() == gray_right.size())
      << "PatchScreening needs two CV_32FC1 views of one size";
  cv::Mat sum, diff, gx;
  cv::add(gray_left, gray_right, sum);
  cv::subtract(gray_left, gray_right, diff);
  cv::Sobel(sum, gx, CV_32F, 1, 0, 3, 1, 0, cv::BORDER_REFLECT_101);
  cv::integral(cv::abs(gx), texture_integral_, CV_64F);
  const cv::Mat mask = (cv::Mat_<float>(3, 3) << 1, -2, 1, -2, 4, -2, 1, -2, 1);
  cv::filter2D(gray_left, noise_left_, CV_32F, mask);
  cv::filter2D(gray_right, noise_right_, CV_32F, mask);
  cv::filter2D(diff, noise_diff_, CV_32F, mask);
  noise_left_ = cv::abs(noise_left_);
  noise_right_ = cv::abs(noise_right_);
  noise_diff_ = cv::abs(noise_diff_);
}

double PatchScreening::Texture(const cv::Rect& r) const {
  const cv::Mat& t = texture_integral_;
  return (t.at<double>(r.y + r.height, r.x + r.width) -
          t.at<double>(r.y, r.x + r.width) - t.at<double>(r.y + r.height, r.x) +
          t.at<double>(r.y, r.x)) /
         r.area();
}

double PatchScreening::NoiseSigma(const cv::Rect& rect) const {
  const double sl = SubsampledNoiseSigma(noise_left_, rect);
  const double sr = SubsampledNoiseSigma(noise_right_, rect);
  return std::sqrt(SmallerNoiseVariance(sl, sr, DifferenceVariance(rect)));
}

double PatchScreening::NoiseSigmaBound(const cv::Rect& rect) const {
  return std::sqrt(DifferenceVariance(rect));
}

double PatchScreening::DifferenceVariance(const cv::Rect& rect) const {
  const double sd = SubsampledNoiseSigma(noise_diff_, rect) / std::sqrt(2.0);
  return sd * sd;
}

double TextureSnr(double texture, double noise_sigma) {
  return texture / (3.91 * std::max(noise_sigma, 1e-6));
}

double PatchScreening::TextureSnr(const cv::Rect& rect) const {
  return dpsfm::TextureSnr(Texture(rect), NoiseSigma(rect));
}

}  // namespace dpsfm
