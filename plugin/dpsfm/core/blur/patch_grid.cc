#include "dpsfm/core/blur/patch_grid.h"
#include "dpsfm/core/util/statistics.h"
#include "dpsfm/core/util/threads.h"

#include <algorithm>
#include <cmath>

namespace dpsfm {

DepthStats DepthStatsOf(std::vector<float>* values) {
  DepthStats stats;
  if (values->empty()) return stats;
  std::vector<float>& v = *values;
  const size_t n = v.size();
  stats.median = UpperMedianInPlace(&v);
  // The median's selection leaves the values below it before it and those
  // above after it: the 10th and 90th percentiles are selected within the
  // two halves (the same values, half the work).
  const size_t m = n / 2;
  auto rank = [&](size_t k) -> double {
    if (k < m) {
      std::nth_element(v.begin(), v.begin() + k, v.begin() + m);
    } else if (k > m) {
      std::nth_element(v.begin() + m + 1, v.begin() + k, v.end());
    }
    return v[k];
  };
  const double p10 = rank(n / 10);
  const double p90 = rank(std::min(n - 1, (9 * n) / 10));
  double mean = 0, sq = 0;
  for (float z : v) mean += z;
  mean /= n;
  for (float z : v) sq += (z - mean) * (z - mean);
  stats.relative_spread = (p90 - p10) / stats.median;
  stats.relative_variance = sq / n / (stats.median * stats.median);
  stats.ok = stats.median > 0 && std::isfinite(stats.median);
  return stats;
}

namespace {

// The lattice positions along one axis of `length` px: patch starts c + k
// stride (c centres one patch), those whose crop (patch plus border on both
// sides) fits. The lattice does not depend on the border, so a larger search
// bound (a wider border) only drops positions at the edges.
std::vector<int> LatticeStarts(int length, int patch, int stride, int border) {
  std::vector<int> starts;
  const int centre = (length - patch) / 2;
  int first = centre - (centre - border >= 0 ? (centre - border) / stride : 0) *
                           stride;
  for (int x = first; x + patch + border <= length; x += stride) {
    if (x - border >= 0) starts.push_back(x);
  }
  return starts;
}

}  // namespace

std::vector<PatchCandidate> MakePatchGrid(const cv::Size& size,
                                          int patch,
                                          int stride,
                                          int border) {
  std::vector<PatchCandidate> candidates;
  for (const int y : LatticeStarts(size.height, patch, stride, border)) {
    for (const int x : LatticeStarts(size.width, patch, stride, border)) {
      PatchCandidate c;
      c.interior = cv::Rect(x, y, patch, patch);
      candidates.push_back(c);
    }
  }
  return candidates;
}

namespace {

// Where MeasurePatchDepths reads depth: a dense map or points, over a DP
// frame of `frame_size`, and the working / frame scale per axis.
struct DepthSource {
  const cv::Mat& map;
  const std::vector<DepthPoint>& points;
  cv::Size frame_size;
  double sx, sy;
};

// MeasurePatchDepths for one candidate.
void MeasurePatchDepth(const DepthSource& source,
                       const PatchDepthOptions& options,
                       PatchCandidate* candidate) {
  const cv::Mat& depth = source.map;
  const double sx = source.sx, sy = source.sy;
  PatchCandidate& c = *candidate;
  // Interior edges in frame pixels: [x / sx, (x + p) / sx).
  const bool dense = !depth.empty();
  const double dw = dense ? depth.cols : 0, dh = dense ? depth.rows : 0;
  std::vector<float> values;
  const double fx0 = c.interior.x / sx,
               fx1 = (c.interior.x + c.interior.width) / sx;
  const double fy0 = c.interior.y / sy,
               fy1 = (c.interior.y + c.interior.height) / sy;
  int total = 0;
  if (dense) {
    const double kx = dw / source.frame_size.width,
                 ky = dh / source.frame_size.height;
    // Depth pixels whose centres fall inside the patch's frame area.
    const int i0 = std::max(0, static_cast<int>(std::ceil(fx0 * kx - 0.5)));
    const int i1 = std::min(static_cast<int>(dw) - 1,
                            static_cast<int>(std::ceil(fx1 * kx - 0.5)) - 1);
    const int j0 = std::max(0, static_cast<int>(std::ceil(fy0 * ky - 0.5)));
    const int j1 = std::min(static_cast<int>(dh) - 1,
                            static_cast<int>(std::ceil(fy1 * ky - 0.5)) - 1);
    // One allocation: a patch's depth pixels grew the vector a dozen times
    // (half a million allocations on a scene of 8 views of 1200 x 800).
    values.reserve(std::max(0, (i1 - i0 + 1) * (j1 - j0 + 1)));
    for (int j = j0; j <= j1; ++j) {
      const float* row = depth.ptr<float>(j);
      for (int i = i0; i <= i1; ++i) {
        ++total;
        if (std::isfinite(row[i]) && row[i] > 0) values.push_back(row[i]);
      }
    }
    if (total == 0 || values.size() < options.min_coverage * total) {
      c.reject = "without depth";
      return;
    }
  } else {
    // Pixel centres at integer frame coordinates: the area
    // [fx0, fx1) in edge coordinates holds centres x + 0.5 in it.
    for (const DepthPoint& point : source.points) {
      const double ex = point.x + 0.5, ey = point.y + 0.5;
      if (ex >= fx0 && ex < fx1 && ey >= fy0 && ey < fy1 &&
          std::isfinite(point.depth) && point.depth > 0) {
        values.push_back(static_cast<float>(point.depth));
      }
    }
    if (static_cast<int>(values.size()) < options.min_points) {
      c.reject = "without depth";
      return;
    }
  }
  c.depth = DepthStatsOf(&values);
  if (!c.depth.ok) {
    c.reject = "without depth";
  } else if (c.depth.relative_spread > options.max_relative_spread) {
    c.reject = "across a depth edge";
  }
}

}  // namespace

void MeasurePatchDepths(const cv::Mat& depth,
                        const std::vector<DepthPoint>& points,
                        const cv::Size& frame_size,
                        double sx,
                        double sy,
                        const PatchDepthOptions& options,
                        std::vector<PatchCandidate>* candidates) {
  const DepthSource source{depth, points, frame_size, sx, sy};
  ParallelFor(
      static_cast<int>(candidates->size()), options.num_threads, [&](int k) {
        MeasurePatchDepth(source, options, &(*candidates)[k]);
      });
}

}  // namespace dpsfm
