#include "dpsfm/core/optics/dp_renderer.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "dpsfm/core/util/check.h"

namespace dpsfm {

bool DPRenderOptions::Check(std::string* failure) const {
  DPSFM_CHECK_OPTION_GT(radius_step_px, 0.0);
  return true;
}

namespace {

void CheckRenderInputs(const cv::Mat& sharp,
                       const cv::Mat& depth,
                       const cv::Mat& radius_px,
                       const DPRenderOptions& options,
                       const cv::Mat* left,
                       const cv::Mat* right) {
  DPSFM_CHECK_OPTIONS(options, "DPRenderOptions");
  DPSFM_CHECK(sharp.type() == CV_32FC1 || sharp.type() == CV_32FC3)
      << "sharp image must be CV_32FC1 or CV_32FC3";
  DPSFM_CHECK(depth.type() == CV_32FC1 && depth.size() == sharp.size())
      << "depth must be CV_32FC1 of the image's size";
  DPSFM_CHECK(radius_px.type() == CV_32FC1 && radius_px.size() == sharp.size())
      << "radius map must be CV_32FC1 of the image's size";
  DPSFM_CHECK(left != nullptr && right != nullptr);
  for (int y = 0; y < sharp.rows; ++y) {
    for (int x = 0; x < sharp.cols; ++x) {
      DPSFM_CHECK(std::isfinite(radius_px.at<float>(y, x)))
          << "non-finite blur radius at " << x << "," << y;
    }
  }
}

// The pixels in radius bins. Additive: each pixel's light is split between
// the two nearest bins in proportion to its position between them (linear
// interpolation of the kernel in r), so the DP disparity, which grows with
// r, varies smoothly across a slanted surface instead of jumping at bin
// edges (a jump of 0.3 x step px would show as a bright or dark line).
// Layers: each pixel belongs to its nearest bin, bins ordered far to near.
struct RadiusBins {
  cv::Mat bin_low;   // CV_32SC1: the pixel's (lower) bin
  cv::Mat fraction;  // CV_32FC1: its share in the bin above (additive)
  std::vector<int> far_to_near;
};

RadiusBins BinPixels(const cv::Mat& depth,
                     const cv::Mat& radius_px,
                     const DPRenderOptions& options) {
  const bool additive =
      options.compositing == DPRenderOptions::Compositing::kAdditive;
  const cv::Mat position = radius_px / options.radius_step_px;
  RadiusBins bins;
  bins.bin_low.create(depth.size(), CV_32SC1);
  bins.fraction.create(depth.size(), CV_32FC1);
  struct Layer {
    double depth_sum = 0;
    int count = 0;
  };
  std::map<int, Layer> layers;
  for (int y = 0; y < depth.rows; ++y) {
    for (int x = 0; x < depth.cols; ++x) {
      const float p = position.at<float>(y, x);
      const int low = additive ? static_cast<int>(std::floor(p))
                               : static_cast<int>(std::lround(p));
      bins.bin_low.at<int>(y, x) = low;
      bins.fraction.at<float>(y, x) = additive ? p - low : 0.f;
      const float d = depth.at<float>(y, x);
      for (const int bin : {low, low + 1}) {
        if (bin > low && !additive) break;
        Layer& layer = layers[bin];
        layer.depth_sum += d > 0 ? d : 1e30;
        ++layer.count;
      }
    }
  }
  // Far to near (background at depth <= 0 first of all); for the additive
  // mode the order does not matter.
  std::vector<std::pair<double, int>> order;
  for (const auto& entry : layers) {
    order.emplace_back(entry.second.depth_sum / entry.second.count,
                       entry.first);
  }
  std::sort(order.rbegin(), order.rend());
  for (const auto& entry : order) bins.far_to_near.push_back(entry.second);
  return bins;
}

// A bin's pixels' weights (CV_32FC1) on `roi`, set to the bin's support
// grown by the kernel's reach: layers are compact (one surface at one
// depth), so they are convolved only around their bounding box, with a
// margin for the reflected border.
cv::Mat LayerWeight(const RadiusBins& bins,
                    int bin,
                    int kernel_radius,
                    bool additive,
                    cv::Rect* roi) {
  const cv::Mat lower = (bins.bin_low == bin);  // weight 1 - fraction (or 1)
  const cv::Mat upper = (bins.bin_low == bin - 1);  // weight fraction
  const cv::Mat support = additive ? (lower | upper) : lower;
  const int margin = kernel_radius + 2;
  *roi = cv::boundingRect(support);
  roi->x -= 2 * margin;
  roi->y -= 2 * margin;
  roi->width += 4 * margin;
  roi->height += 4 * margin;
  *roi &= cv::Rect(0, 0, bins.bin_low.cols, bins.bin_low.rows);
  cv::Mat weight;
  if (additive) {
    cv::Mat low_weight, high_weight;
    cv::Mat(1.0 - bins.fraction(*roi)).copyTo(low_weight);
    low_weight.setTo(0, ~lower(*roi));
    bins.fraction(*roi).copyTo(high_weight);
    high_weight.setTo(0, ~upper(*roi));
    weight = low_weight + high_weight;
  } else {
    lower(*roi).convertTo(weight, CV_32F, 1.0 / 255.0);
  }
  return weight;
}

// The matrix with its one channel repeated to `channels`.
cv::Mat WithChannels(const cv::Mat& one, int channels) {
  if (channels == 1) return one;
  cv::Mat out;
  cv::merge(std::vector<cv::Mat>(channels, one), out);
  return out;
}

// "Over" compositing of a layer blurred by a view's kernel onto the view
// `out`: the nearer layer hides what lies behind it, by its coverage (the
// layer's mask blurred by the kernel, rescaled to [0, 1] by the view's share
// of the light). Both terms are at the view's share of the light.
void CompositeOver(const cv::Mat& layer,
                   const cv::Mat& weight,
                   const cv::Mat& kernel,
                   cv::Mat* out) {
  const double share = cv::sum(kernel)[0];
  cv::Mat coverage = ConvolvePsf(weight, kernel) / share;
  cv::min(coverage, 1.0, coverage);
  const cv::Mat coverage_c = WithChannels(coverage, out->channels());
  const cv::Mat composite =
      out->mul(cv::Scalar::all(1.0) - coverage_c) + ConvolvePsf(layer, kernel);
  composite.copyTo(*out);
}

}  // namespace

void RenderDPViews(const cv::Mat& sharp,
                   const cv::Mat& depth,
                   const cv::Mat& radius_px,
                   const DPPsfModel& psf,
                   const DPRenderOptions& options,
                   cv::Mat* left,
                   cv::Mat* right) {
  CheckRenderInputs(sharp, depth, radius_px, options, left, right);
  *left = cv::Mat::zeros(sharp.size(), sharp.type());
  *right = cv::Mat::zeros(sharp.size(), sharp.type());
  const bool additive =
      options.compositing == DPRenderOptions::Compositing::kAdditive;
  const RadiusBins bins = BinPixels(depth, radius_px, options);
  for (const int bin : bins.far_to_near) {
    const double radius = bin * options.radius_step_px;
    cv::Rect roi;
    const cv::Mat weight =
        LayerWeight(bins, bin, psf.KernelRadius(radius), additive, &roi);
    const cv::Mat layer =
        sharp(roi).mul(WithChannels(weight, sharp.channels()));
    const DPKernels kernels = psf.Kernels(radius);
    for (int view = 0; view < 2; ++view) {
      const cv::Mat& kernel = view == 0 ? kernels.left : kernels.right;
      cv::Mat out = (view == 0 ? *left : *right)(roi);
      if (additive) {
        out += ConvolvePsf(layer, kernel);
      } else {
        CompositeOver(layer, weight, kernel, &out);
      }
    }
  }
}

}  // namespace dpsfm
