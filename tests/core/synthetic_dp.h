// Synthetic dual-pixel data for tests: a seeded procedural texture and a DP
// renderer that blurs an all-in-focus image with the left/right kernels of any
// DPPsfModel, for one blur radius or a piecewise-constant radius map, with
// optional left/right gains and Gaussian noise. Header-only; deterministic for
// a given seed on a given platform (cv::RNG).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <map>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "dpsfm/core/optics/dp_psf.h"
#include "dpsfm/core/util/check.h"

namespace dpsfm {
namespace test {

struct TextureOptions {
  // Number of octaves of value noise; octave k has cells of
  // `coarsest_cell_px / 2^k` pixels and amplitude `persistence^k`.
  int octaves = 5;
  double coarsest_cell_px = 32;
  double persistence = 0.7;
  // Random axis-aligned rectangles and disks of constant intensity pasted on
  // top (step edges, as real scenes have), per 100 x 100 pixels.
  double shapes_per_10k_px = 3;
  // Output intensity range.
  double min_value = 0.1;
  double max_value = 0.9;
  // Channels of the output: 1 (CV_32FC1) or 3 (CV_32FC3, channels with
  // correlated but not identical content).
  int channels = 1;
};

// Multi-scale procedural texture in [min_value, max_value].
inline cv::Mat MakeTexture(const cv::Size& size,
                           uint64_t seed,
                           const TextureOptions& options = TextureOptions()) {
  DPSFM_CHECK(size.width > 0 && size.height > 0) << "empty texture size";
  DPSFM_CHECK(options.channels == 1 || options.channels == 3)
      << "channels must be 1 or 3";
  DPSFM_CHECK(options.octaves >= 1 && options.coarsest_cell_px >= 1)
      << "bad texture octaves";
  cv::RNG rng(seed == 0 ? 0x9e3779b97f4a7c15ULL : seed);
  std::vector<cv::Mat> planes;
  cv::Mat base;
  for (int c = 0; c < options.channels; ++c) {
    cv::Mat image = cv::Mat::zeros(size, CV_32FC1);
    double amplitude = 1.0;
    for (int k = 0; k < options.octaves; ++k) {
      const double cell = std::max(1.0, options.coarsest_cell_px / (1 << k));
      const cv::Size grid(static_cast<int>(std::ceil(size.width / cell)) + 4,
                          static_cast<int>(std::ceil(size.height / cell)) + 4);
      cv::Mat noise(grid, CV_32FC1);
      rng.fill(noise, cv::RNG::UNIFORM, -1.0, 1.0);
      cv::Mat up;
      cv::resize(noise,
                 up,
                 cv::Size(static_cast<int>(grid.width * cell),
                          static_cast<int>(grid.height * cell)),
                 0,
                 0,
                 cell > 1 ? cv::INTER_CUBIC : cv::INTER_NEAREST);
      // Random offset so octaves are not aligned to the same lattice.
      const int ox = rng.uniform(0, std::max(1, up.cols - size.width));
      const int oy = rng.uniform(0, std::max(1, up.rows - size.height));
      image += amplitude * up(cv::Rect(ox, oy, size.width, size.height));
      amplitude *= options.persistence;
    }
    const int num_shapes = static_cast<int>(
        std::round(options.shapes_per_10k_px * size.area() / 1e4));
    for (int s = 0; s < num_shapes; ++s) {
      const double value = rng.uniform(-1.5, 1.5);
      // One draw at a time (arguments are evaluated in an order compilers
      // choose), y first: the order GCC drew them in when the tests'
      // tolerances were set.
      const int y = rng.uniform(0, size.height);
      const int x = rng.uniform(0, size.width);
      const cv::Point centre(x, y);
      const int extent =
          rng.uniform(3, std::max(4, std::min(size.width, size.height) / 4));
      if (rng.uniform(0, 2) == 0) {
        cv::rectangle(image,
                      cv::Rect(centre.x - extent / 2,
                               centre.y - extent / 3,
                               extent,
                               std::max(2, 2 * extent / 3)),
                      cv::Scalar(value),
                      cv::FILLED);
      } else {
        cv::circle(image,
                   centre,
                   extent / 2,
                   cv::Scalar(value),
                   cv::FILLED,
                   cv::LINE_AA);
      }
    }
    if (c == 0) {
      base = image;
    } else {
      // Colour channels share most structure (as in natural images).
      image = 0.7 * base + 0.3 * image;
    }
    planes.push_back(image);
  }
  cv::Mat texture;
  cv::merge(planes, texture);
  double lo = 0, hi = 0;
  cv::minMaxLoc(texture.reshape(1), &lo, &hi);
  const double scale =
      hi > lo ? (options.max_value - options.min_value) / (hi - lo) : 0.0;
  texture.convertTo(
      texture, texture.type(), scale, options.min_value - lo * scale);
  return texture;
}

struct RenderOptions {
  // Multiplicative gain of each view (before noise), e.g. 1.1 / 0.9 to mimic
  // the left/right vignetting difference of real DP sensors.
  double left_gain = 1.0;
  double right_gain = 1.0;
  // Standard deviation of additive i.i.d. Gaussian noise on each view, in the
  // image's intensity units; 0 = none.
  double noise_sigma = 0.0;
  uint64_t noise_seed = 1;
  // Clip the output to [0, 1] (after noise), like an encoded image.
  bool clip = false;
};

struct DPPair {
  cv::Mat left;
  cv::Mat right;
};

namespace internal {

inline void FinishViews(const RenderOptions& options, DPPair* pair) {
  pair->left *= options.left_gain;
  pair->right *= options.right_gain;
  if (options.noise_sigma > 0) {
    cv::RNG rng(options.noise_seed == 0 ? 12345 : options.noise_seed);
    for (cv::Mat* view : {&pair->left, &pair->right}) {
      cv::Mat noise(view->size(), view->type());
      rng.fill(noise, cv::RNG::NORMAL, 0.0, options.noise_sigma);
      *view += noise;
    }
  }
  if (options.clip) {
    for (cv::Mat* view : {&pair->left, &pair->right}) {
      cv::min(*view, 1.0, *view);
      cv::max(*view, 0.0, *view);
    }
  }
}

}  // namespace internal

// Renders the DP views of an all-in-focus image (CV_32FC1 or CV_32FC3) at one
// signed blur radius: left = sharp * H_l(r), right = sharp * H_r(r).
inline DPPair RenderDP(const cv::Mat& sharp,
                       const DPPsfModel& psf,
                       double signed_radius_px,
                       const RenderOptions& options = RenderOptions()) {
  const DPKernels kernels = psf.Kernels(signed_radius_px);
  DPPair pair;
  pair.left = ConvolvePsf(sharp, kernels.left);
  pair.right = ConvolvePsf(sharp, kernels.right);
  internal::FinishViews(options, &pair);
  return pair;
}

// Renders with a piecewise-constant radius map (CV_32FC1 or CV_64FC1, same
// size as `sharp`): every output pixel takes the kernels of its own radius
// ("gather": out(x) = sum_d sharp(x - d) H_{r(x)}(d)). Inside a region of
// constant radius, farther than that radius's kernel half-size from any other
// region, this equals RenderDP at that radius exactly. At most 256 distinct
// radii (each costs two full-image convolutions).
inline DPPair RenderDP(const cv::Mat& sharp,
                       const DPPsfModel& psf,
                       const cv::Mat& radius_map,
                       const RenderOptions& options = RenderOptions()) {
  DPSFM_CHECK(radius_map.size() == sharp.size())
      << "radius map and image differ in size";
  DPSFM_CHECK(radius_map.type() == CV_32FC1 || radius_map.type() == CV_64FC1)
      << "radius map must be CV_32FC1 or CV_64FC1";
  cv::Mat radii;
  radius_map.convertTo(radii, CV_64FC1);
  std::map<double, cv::Mat> masks;
  for (int y = 0; y < radii.rows; ++y) {
    for (int x = 0; x < radii.cols; ++x) {
      const double r = radii.at<double>(y, x);
      DPSFM_CHECK(std::isfinite(r)) << "non-finite radius in the map";
      auto it = masks.find(r);
      if (it == masks.end()) {
        DPSFM_CHECK_LT(masks.size(), 256u)
            << "radius map has too many distinct values (not piecewise "
               "constant?)";
        it = masks.emplace(r, cv::Mat::zeros(radii.size(), CV_8UC1)).first;
      }
      it->second.at<uint8_t>(y, x) = 255;
    }
  }
  DPPair pair;
  pair.left = cv::Mat::zeros(sharp.size(), sharp.type());
  pair.right = cv::Mat::zeros(sharp.size(), sharp.type());
  for (const auto& entry : masks) {
    const DPKernels kernels = psf.Kernels(entry.first);
    ConvolvePsf(sharp, kernels.left).copyTo(pair.left, entry.second);
    ConvolvePsf(sharp, kernels.right).copyTo(pair.right, entry.second);
  }
  internal::FinishViews(options, &pair);
  return pair;
}

// Luma of a CV_32FC3 image (Rec. 601 weights on the channels in order), or a
// copy of a CV_32FC1 one.
inline cv::Mat ToGray(const cv::Mat& image) {
  if (image.channels() == 1) {
    return image.clone();
  }
  cv::Mat gray;
  cv::transform(image, gray, cv::Matx13f(0.299f, 0.587f, 0.114f));
  return gray;
}

// A DP kernel pair outside every family the estimator fits, as a measured
// calibration would give it (far side: the left view leans towards -x),
// each pixel sampled 4 x 4: an ellipse x^2 + (y / aspect)^2 <= half^2,
// optionally cut by a second disk offset by cut * half along x (a
// cat-eye), light weighted by 1 + rim rho^4 (a bright rim), divided
// between the views by a sigmoid of the given strength along an axis
// rotated by rotation_deg.
struct KernelPair {
  cv::Mat left, right;
};
inline KernelPair SoftSplitKernels(int half,
                                   double aspect,
                                   double rotation_deg,
                                   double strength,
                                   double cut = 0,
                                   double rim = 0) {
  KernelPair k;
  k.left = cv::Mat::zeros(2 * half + 1, 2 * half + 1, CV_32FC1);
  k.right = k.left.clone();
  const double c = std::cos(rotation_deg * M_PI / 180);
  const double sn = std::sin(rotation_deg * M_PI / 180);
  const double h2 = static_cast<double>(half) * half;
  for (int i = -half; i <= half; ++i) {
    for (int j = -half; j <= half; ++j) {
      double wl = 0, wr = 0;
      for (int a = 0; a < 4; ++a) {
        for (int b = 0; b < 4; ++b) {
          const double x = j - 0.375 + 0.25 * b, y = i - 0.375 + 0.25 * a;
          const double rho2 = (x * x + (y / aspect) * (y / aspect)) / h2;
          if (rho2 > 1) continue;
          const double dx = x - cut * half;
          if (cut > 0 && dx * dx + y * y > h2) continue;
          const double t = (c * x + sn * y) / half;
          const double plus = 1 / (1 + std::exp(-strength * t));
          const double w = 1 + rim * rho2 * rho2;
          wl += w * (1 - plus);
          wr += w * plus;
        }
      }
      k.left.at<float>(i + half, j + half) = static_cast<float>(wl);
      k.right.at<float>(i + half, j + half) = static_cast<float>(wr);
    }
  }
  return k;
}

// True convolution through OpenCV's correlation (the kernel rotated by 180
// degrees), sharing nothing with the code under test: the oracle of the
// kernel-measurement tests.
inline cv::Mat ConvolveWithOpenCV(const cv::Mat& image, const cv::Mat& psf) {
  cv::Mat flipped, out;
  cv::flip(psf, flipped, -1);
  cv::filter2D(
      image, out, CV_32F, flipped, cv::Point(-1, -1), 0, cv::BORDER_REFLECT);
  return out;
}

}  // namespace test
}  // namespace dpsfm
