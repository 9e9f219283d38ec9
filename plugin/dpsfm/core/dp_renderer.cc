#include "dpsfm/core/dp_renderer.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "dpsfm/core/check.h"

namespace dpsfm {

bool DPRenderOptions::Check() const {
  DPSFM_CHECK_GT(radius_step_px, 0.0);
  return true;
}

void RenderDPViews(const cv::Mat& sharp,
                   const cv::Mat& depth,
                   const cv::Mat& radius_px,
                   const DPPsfModel& psf,
                   const DPRenderOptions& options,
                   cv::Mat* left,
                   cv::Mat* right) {
  options.Check();
  DPSFM_CHECK(sharp.type() == CV_32FC1 || sharp.type() == CV_32FC3)
      << "sharp image must be CV_32FC1 or CV_32FC3";
  DPSFM_CHECK(depth.type() == CV_32FC1 && depth.size() == sharp.size())
      << "depth must be CV_32FC1 of the image's size";
  DPSFM_CHECK(radius_px.type() == CV_32FC1 && radius_px.size() == sharp.size())
      << "radius map must be CV_32FC1 of the image's size";
  DPSFM_CHECK(left != nullptr && right != nullptr);

  // Group pixels into radius bins; order bins by the mean depth of their
  // pixels, farthest first (background at depth <= 0 goes first of all).
  struct Layer {
    double depth_sum = 0;
    int count = 0;
  };
  std::map<int, Layer> layers;
  cv::Mat bin_of(sharp.size(), CV_32SC1);
  for (int y = 0; y < sharp.rows; ++y) {
    for (int x = 0; x < sharp.cols; ++x) {
      const float r = radius_px.at<float>(y, x);
      DPSFM_CHECK(std::isfinite(r)) << "non-finite blur radius at " << x << ","
                                    << y;
      const int bin =
          static_cast<int>(std::lround(r / options.radius_step_px));
      bin_of.at<int>(y, x) = bin;
      const float d = depth.at<float>(y, x);
      Layer& layer = layers[bin];
      layer.depth_sum += d > 0 ? d : 1e30;
      ++layer.count;
    }
  }
  std::vector<std::pair<double, int>> order;
  for (const auto& entry : layers) {
    order.emplace_back(entry.second.depth_sum / entry.second.count,
                       entry.first);
  }
  std::sort(order.rbegin(), order.rend());

  const int channels = sharp.channels();
  *left = cv::Mat::zeros(sharp.size(), sharp.type());
  *right = cv::Mat::zeros(sharp.size(), sharp.type());
  const cv::Rect image_rect(0, 0, sharp.cols, sharp.rows);
  for (const auto& entry : order) {
    const int bin = entry.second;
    const double radius = bin * options.radius_step_px;
    const cv::Mat mask_u8 = (bin_of == bin);
    // Layers are compact (one surface at one depth), so convolve only around
    // the layer: its bounding box grown by the kernel radius plus a margin
    // for the reflected border.
    const int margin = psf.KernelRadius(radius) + 2;
    cv::Rect roi = cv::boundingRect(mask_u8);
    roi.x -= 2 * margin;
    roi.y -= 2 * margin;
    roi.width += 4 * margin;
    roi.height += 4 * margin;
    roi &= image_rect;
    cv::Mat mask;
    mask_u8(roi).convertTo(mask, CV_32F, 1.0 / 255.0);
    cv::Mat mask_c = mask;
    if (channels == 3) {
      cv::merge(std::vector<cv::Mat>(3, mask), mask_c);
    }
    const cv::Mat layer = sharp(roi).mul(mask_c);
    const DPKernels kernels = psf.Kernels(radius);
    for (int view = 0; view < 2; ++view) {
      const cv::Mat& kernel = view == 0 ? kernels.left : kernels.right;
      cv::Mat out = (view == 0 ? *left : *right)(roi);
      if (options.compositing == DPRenderOptions::Compositing::kAdditive) {
        out += ConvolvePsf(layer, kernel);
        continue;
      }
      // Coverage of this layer in this view: the layer's mask blurred by the
      // view's kernel, rescaled to [0, 1] by the view's share of the light.
      const double share = cv::sum(kernel)[0];
      cv::Mat coverage = ConvolvePsf(mask, kernel) / share;
      cv::min(coverage, 1.0, coverage);
      cv::Mat coverage_c = coverage;
      if (channels == 3) {
        cv::merge(std::vector<cv::Mat>(3, coverage), coverage_c);
      }
      // "Over" compositing: the nearer layer hides what lies behind it. Both
      // terms are at the view's share of the light.
      const cv::Mat composite =
          out.mul(1.0 - coverage_c) + ConvolvePsf(layer, kernel);
      composite.copyTo(out);
    }
  }
}

}  // namespace dpsfm
