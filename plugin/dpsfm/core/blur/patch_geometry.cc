// DefaultPatchGeometry and PatchGeometryForRadius (declared in
// blur_estimation.h): the patch size, stride and search bound for a frame.
#include "dpsfm/core/blur/blur_estimation.h"

#include <algorithm>
#include <cmath>

#include "dpsfm/core/util/check.h"

namespace dpsfm {

namespace {

// The search bound in px of the whole frame: the reference rule (anchors
// below) applied at the reference resize 1/k, smallest integer k with a
// working short side <= 2800 px, then expressed in frame px.
double FrameRadiusBound(const cv::Size& frame_size) {
  DPSFM_CHECK(frame_size.width > 0 && frame_size.height > 0)
      << "empty frame size";
  const int frame_short = std::min(frame_size.width, frame_size.height);
  const int k = std::max(1, static_cast<int>(std::ceil(frame_short / 2800.0)));
  const double short_side = static_cast<double>(frame_short) / k;
  // Anchors: phone (1512 px, |r| <= 10), DSLR at 0.5 (2240 px, |r| <= 20).
  double max_radius;
  if (short_side <= 1512) {
    max_radius = 10.0 * short_side / 1512;
  } else if (short_side <= 2240) {
    max_radius = 10.0 + (short_side - 1512) * 10.0 / (2240 - 1512);
  } else {
    max_radius = 20.0 * short_side / 2240;
  }
  return max_radius * k;
}

}  // namespace

PatchGeometry DefaultPatchGeometry(const cv::Size& frame_size) {
  // Work at the coarsest integer reduction that keeps the search bound near
  // the phone anchor's 10 px: blur of a few pixels or more has no detail
  // finer than the reduced grid, and area averaging keeps the shift
  // information (noise falls as the pixels grow), so the scale does not
  // change while a patch's FFTs shrink by k^2 (docs/benchmark.md: 3000x2000
  // frames at 1/2 give the full-resolution scale and interval at 1/6 of the
  // blur stage's cost). Frames with a short side below ~1880 px keep their
  // resolution.
  const double bound = FrameRadiusBound(frame_size);
  const int k = std::max(1, static_cast<int>(std::lround(bound / 10.0)));
  return DefaultPatchGeometry(frame_size, 1.0 / k);
}

PatchGeometry DefaultPatchGeometry(const cv::Size& frame_size,
                                   double resize_factor) {
  DPSFM_CHECK(resize_factor > 0 && resize_factor <= 1)
      << "resize factor must be in (0, 1], got " << resize_factor;
  const double max_radius = FrameRadiusBound(frame_size) * resize_factor;
  // Half-pixel steps keep the bound on the blur estimator's kernel grid.
  return PatchGeometryForRadius(std::max(3.0, std::round(2 * max_radius) / 2),
                                resize_factor);
}

PatchGeometry PatchGeometryForRadius(double max_radius, double resize_factor) {
  DPSFM_CHECK(max_radius >= 1 && std::isfinite(max_radius))
      << "radius bound must be at least 1 px, got " << max_radius;
  PatchGeometry geometry;
  geometry.max_radius_px = max_radius;
  const double patch = std::max(6 * max_radius - 9, 2 * max_radius + 21);
  geometry.patch_size = 2 * static_cast<int>(std::round((patch - 1) / 2)) + 1;
  geometry.stride = static_cast<int>(std::round(2 * max_radius + 7));
  geometry.resize_factor = resize_factor;
  return geometry;
}

}  // namespace dpsfm
