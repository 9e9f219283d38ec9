#include "dpsfm/colmap/report/plot_axes.h"

#include <cmath>
#include <cstdio>

#include <opencv2/imgproc.hpp>

#include "dpsfm/colmap/report/plot_text.h"
#include "dpsfm/core/util/statistics.h"

namespace dpsfm {
namespace plot {

void PadRange(Range* range, double fraction) {
  if (!range->Valid()) {
    range->lo = 0;
    range->hi = 1;
    return;
  }
  double span = range->hi - range->lo;
  if (!(span > 1e-12 * std::max(1.0, std::abs(range->hi)))) {
    span = range->lo != 0 ? 0.2 * std::abs(range->lo) : 1.0;
    range->lo -= 0.5 * span;
    range->hi += 0.5 * span;
    return;
  }
  range->lo -= fraction * span;
  range->hi += fraction * span;
}

Range RobustRange(const std::vector<double>& values) {
  Range full;
  for (const double v : values) full.Add(v);
  if (!full.Valid()) return full;
  const double lo = NearestRankQuantile(values, 0.01),
               hi = NearestRankQuantile(values, 0.99);
  const double span = hi - lo;
  Range range;
  range.lo = std::max(full.lo, lo - 0.5 * span);
  range.hi = std::min(full.hi, hi + 0.5 * span);
  return range;
}

std::vector<double> NiceTicks(double lo, double hi, int target, double* step) {
  std::vector<double> ticks;
  *step = 0;
  if (!Finite(lo) || !Finite(hi) || !(hi > lo)) return ticks;
  const double raw = (hi - lo) / std::max(target, 1);
  const double magnitude = std::pow(10.0, std::floor(std::log10(raw)));
  const double r = raw / magnitude;
  const double nice = r < 1.5 ? 1 : r < 3 ? 2 : r < 7 ? 5 : 10;
  *step = nice * magnitude;
  if (!(*step > 0) || !Finite(*step)) return ticks;
  const double first = std::ceil(lo / *step - 1e-9);
  for (int i = 0; i < 100; ++i) {
    double v = (first + i) * *step;
    if (v > hi + 1e-9 * *step) break;
    if (std::abs(v) < 1e-9 * *step) v = 0;
    ticks.push_back(v);
  }
  return ticks;
}

std::string FormatTick(double value, double step) {
  const double a = std::max(std::abs(value), step);
  if (step < 1e-5 || a >= 1e6) return Format("%.3g", value);
  const int decimals =
      std::max(0, static_cast<int>(-std::floor(std::log10(step) + 1e-9)));
  char buffer[64];
  std::snprintf(buffer, sizeof(buffer), "%.*f", decimals, value);
  return buffer;
}

void DrawAxes(cv::Mat& canvas,
              const Axes& axes,
              const std::string& x_label,
              const std::string& y_label,
              bool x_ticks_shown,
              bool y_ticks_shown) {
  const cv::Rect& a = axes.area;
  const double tick_font = 0.45;
  double x_step = 0, y_step = 0;
  const std::vector<double> x_ticks =
      x_ticks_shown
          ? NiceTicks(axes.x.lo, axes.x.hi, std::max(3, a.width / 90), &x_step)
          : std::vector<double>();
  const std::vector<double> y_tick_values =
      y_ticks_shown
          ? NiceTicks(axes.y.lo, axes.y.hi, std::max(3, a.height / 70), &y_step)
          : std::vector<double>();
  for (const double t : x_ticks) {
    const double px = axes.ToPixel(t, 0).x;
    DrawSegment(canvas,
                {px, double(a.y)},
                {px, double(a.y + a.height)},
                kGridColour,
                1);
    DrawSegment(canvas,
                {px, double(a.y + a.height)},
                {px, double(a.y + a.height + 5)},
                kAxisColour,
                1);
    PutText(canvas,
            FormatTick(t, x_step),
            {static_cast<int>(std::lround(px)), a.y + a.height + 21},
            tick_font,
            kTextColour,
            1,
            Align::kCenter);
  }
  int widest_label = 0;
  for (const double t : y_tick_values) {
    const double py = axes.ToPixel(0, t).y;
    DrawSegment(
        canvas, {double(a.x), py}, {double(a.x + a.width), py}, kGridColour, 1);
    DrawSegment(
        canvas, {double(a.x - 5), py}, {double(a.x), py}, kAxisColour, 1);
    const std::string label = FormatTick(t, y_step);
    widest_label = std::max(widest_label, TextSize(label, tick_font, 1).width);
    PutText(canvas,
            label,
            {a.x - 9, static_cast<int>(std::lround(py)) + 5},
            tick_font,
            kTextColour,
            1,
            Align::kRight);
  }
  cv::rectangle(canvas, a, kAxisColour, 1, cv::LINE_AA);
  PutText(canvas,
          x_label,
          {a.x + a.width / 2, a.y + a.height + 46},
          0.55,
          kTextColour,
          1,
          Align::kCenter);
  if (!y_label.empty()) {
    PutVerticalText(canvas,
                    y_label,
                    {a.x - widest_label - 26, a.y + a.height / 2},
                    0.55,
                    kTextColour);
  }
}

void DrawNoData(cv::Mat& canvas,
                const cv::Rect& area,
                const std::string& message) {
  const std::vector<std::string> lines =
      WrapText(message, 0.6, 1, area.width - 40, 4);
  int y = area.y + area.height / 2 - static_cast<int>(lines.size()) * 12 + 8;
  for (const std::string& line : lines) {
    PutText(canvas,
            line,
            {area.x + area.width / 2, y},
            0.6,
            kMutedText,
            1,
            Align::kCenter);
    y += 26;
  }
}

}  // namespace plot
}  // namespace dpsfm
