// Data ranges, nice ticks and axes (a plot area with the data range it
// shows) for the report pictures.
#pragma once

#include <algorithm>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "dpsfm/colmap/report/plot_canvas.h"

namespace dpsfm {
namespace plot {

// The finite values added so far; empty (not Valid) until one is.
struct Range {
  double lo = kInf;
  double hi = -kInf;
  void Add(double v) {
    if (!Finite(v)) return;
    lo = std::min(lo, v);
    hi = std::max(hi, v);
  }
  bool Valid() const { return lo <= hi; }
};

// Pads a data range by `fraction` on both sides; a degenerate or empty range
// becomes a sensible one so that the axes can still be drawn.
void PadRange(Range* range, double fraction);

// Axis range for data that may hold a few wild values (a blur estimate at
// 1e300, a depth near zero): the 1st-99th percentile range widened by half
// its span, never beyond the data, so ordinary tails stay on the axes.
Range RobustRange(const std::vector<double>& values);

// Ticks at 1, 2 or 5 times a power of ten, about `target` of them, between
// lo and hi; *step is their spacing (0 when there are none).
std::vector<double> NiceTicks(double lo, double hi, int target, double* step);

// A tick label with as many decimals as `step` needs.
std::string FormatTick(double value, double step);

// A plot area and the data range it shows.
struct Axes {
  cv::Rect area;
  Range x, y;

  cv::Point2d ToPixel(double vx, double vy) const {
    return {area.x + (vx - x.lo) / (x.hi - x.lo) * area.width,
            area.y + (y.hi - vy) / (y.hi - y.lo) * area.height};
  }
  // The plot area as its own image: drawing into it clips at the frame.
  cv::Mat Roi(cv::Mat& canvas) const { return canvas(area); }
  cv::Point2d ToLocal(double vx, double vy) const {
    return ToPixel(vx, vy) - cv::Point2d(area.x, area.y);
  }
};

// Grid, frame, ticks with labels and axis labels; without ticks for an axis
// that shows no data (made-up numbers would mislead).
void DrawAxes(cv::Mat& canvas,
              const Axes& axes,
              const std::string& x_label,
              const std::string& y_label,
              bool x_ticks_shown = true,
              bool y_ticks_shown = true);

// A message centred in `area` (wrapped to at most 4 lines), where a plot has
// no data to show.
void DrawNoData(cv::Mat& canvas,
                const cv::Rect& area,
                const std::string& message);

}  // namespace plot
}  // namespace dpsfm
