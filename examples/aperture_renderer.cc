#include "examples/aperture_renderer.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <utility>
#include <vector>

#include "dpsfm/core/util/threads.h"

namespace dpsfm {
namespace examples {
namespace {

// Adds `value` (per channel) times `weight` to the pixel whose area holds
// the point (x, y) (pixel centres at whole coordinates): a pixel collects
// the light that lands on it, as a photodiode does.
void Deposit(double x,
             double y,
             const float* value,
             double weight,
             int channels,
             cv::Mat* out) {
  const int px = static_cast<int>(std::floor(x + 0.5));
  const int py = static_cast<int>(std::floor(y + 0.5));
  if (px < 0 || py < 0 || px >= out->cols || py >= out->rows) return;
  float* dst = out->ptr<float>(py) + px * channels;
  for (int c = 0; c < channels; ++c) {
    dst[c] += static_cast<float>(weight * value[c]);
  }
}

// The points of a square lattice of `across` x `across` over [-1, 1]^2
// (cell centres) that lie in the unit disk.
std::vector<std::pair<double, double>> DiskLattice(int across) {
  std::vector<std::pair<double, double>> points;
  for (int i = 0; i < across; ++i) {
    for (int j = 0; j < across; ++j) {
      const double ux = -1 + (i + 0.5) * 2 / across;
      const double uy = -1 + (j + 0.5) * 2 / across;
      if (ux * ux + uy * uy <= 1) points.emplace_back(ux, uy);
    }
  }
  return points;
}

// The rows [row_begin, row_end) of `sharp` sent through the aperture, into
// *left and *right. The aperture points of a pixel: a square lattice over
// the unit disk, so fine that their landing points lie at most
// 1 / subsamples_per_pixel apart on the sensor (and at least
// kMinPointsAcross across the disk); each carries an equal share of the
// pixel's light.
void RenderRows(const cv::Mat& sharp,
                const cv::Mat& radius_px,
                const ApertureRenderOptions& options,
                int row_begin,
                int row_end,
                cv::Mat* left,
                cv::Mat* right) {
  constexpr int kMinPointsAcross = 32;
  const int channels = sharp.channels();
  std::vector<std::pair<double, double>> points;
  int points_across = 0;  // the lattice `points` holds
  for (int y = row_begin; y < row_end; ++y) {
    for (int x = 0; x < sharp.cols; ++x) {
      const float* value = sharp.ptr<float>(y) + x * channels;
      const double r = radius_px.at<float>(y, x);
      const int across =
          std::max(kMinPointsAcross,
                   static_cast<int>(std::ceil(2 * std::abs(r) *
                                              options.subsamples_per_pixel)));
      if (across != points_across) {
        points = DiskLattice(across);
        points_across = across;
      }
      const double share = 1.0 / points.size();
      for (const auto& [ux, uy] : points) {
        const double to_left =
            ux < 0 ? 1 - options.crosstalk : options.crosstalk;
        const double lx = x + r * ux, ly = y + r * uy;
        Deposit(lx, ly, value, share * to_left, channels, left);
        Deposit(lx, ly, value, share * (1 - to_left), channels, right);
      }
    }
  }
}

}  // namespace

double ThinLensBlurRadiusPx(double focal_length_mm,
                            double f_number,
                            double pixel_pitch_mm,
                            double focus_mm,
                            double depth_mm) {
  const double f = focal_length_mm;
  const double v_focus = 1 / (1 / f - 1 / focus_mm);
  const double v_point = 1 / (1 / f - 1 / depth_mm);
  const double diameter = (f / f_number) * (v_focus - v_point) / v_point;
  return diameter / 2 / pixel_pitch_mm;
}

void RenderDPByApertureSampling(const cv::Mat& sharp,
                                const cv::Mat& radius_px,
                                const ApertureRenderOptions& options,
                                cv::Mat* left,
                                cv::Mat* right) {
  if ((sharp.type() != CV_32FC1 && sharp.type() != CV_32FC3) ||
      radius_px.type() != CV_32FC1 || radius_px.size() != sharp.size() ||
      options.subsamples_per_pixel < 1 || !(options.crosstalk >= 0) ||
      !(options.crosstalk <= 0.5)) {
    throw std::invalid_argument(
        "aperture rendering needs a CV_32FC1/3 image, a CV_32FC1 radius map "
        "of its size, subsamples_per_pixel >= 1 and crosstalk in [0, 0.5]");
  }
  // Row blocks, each into its own pair of frames (light crosses blocks),
  // summed at the end in order: the same frames on any number of threads.
  const int blocks = 4;
  std::vector<cv::Mat> lefts(blocks), rights(blocks);
  ParallelFor(blocks, options.num_threads, [&](int b) {
    lefts[b].create(sharp.size(), sharp.type());
    rights[b].create(sharp.size(), sharp.type());
    lefts[b].setTo(cv::Scalar::all(0));
    rights[b].setTo(cv::Scalar::all(0));
    RenderRows(sharp,
               radius_px,
               options,
               sharp.rows * b / blocks,
               sharp.rows * (b + 1) / blocks,
               &lefts[b],
               &rights[b]);
  });
  *left = lefts[0];
  *right = rights[0];
  for (int b = 1; b < blocks; ++b) {
    *left += lefts[b];
    *right += rights[b];
  }
}

}  // namespace examples
}  // namespace dpsfm
