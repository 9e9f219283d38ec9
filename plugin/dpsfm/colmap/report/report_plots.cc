#include "dpsfm/colmap/report/report_plots.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <set>
#include <sstream>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "dpsfm/core/blur/blur_estimation.h"
#include "dpsfm/core/optics/lens_model.h"
#include "dpsfm/core/util/statistics.h"

namespace dpsfm {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr int kFont = cv::FONT_HERSHEY_SIMPLEX;
// Sub-pixel precision of drawn geometry (cv::line & co. take fixed point).
constexpr int kShift = 4;
constexpr double kShiftScale = 1 << kShift;

const cv::Scalar kWhite(255, 255, 255);
const cv::Scalar kTextColour(30, 30, 30);
const cv::Scalar kMutedText(90, 90, 90);
const cv::Scalar kFailureColour(30, 30, 190);
const cv::Scalar kAxisColour(70, 70, 70);
const cv::Scalar kGridColour(232, 232, 232);

// Matplotlib's tab10 (BGR): distinct for the first ten views, familiar to
// anyone who reads plots.
const cv::Scalar kPalette[] = {{180, 119, 31},
                               {14, 127, 255},
                               {44, 160, 44},
                               {40, 39, 214},
                               {189, 103, 148},
                               {75, 86, 140},
                               {194, 119, 227},
                               {127, 127, 127},
                               {34, 189, 188},
                               {207, 190, 23}};
constexpr int kNumPaletteColours = 10;
const cv::Scalar kOtherViewsColour(200, 200, 200);

bool Finite(double v) { return std::isfinite(v); }

double Clamp(double v, double lo, double hi) {
  return std::min(std::max(v, lo), hi);
}

// ---------------------------------------------------------------- Text ---

// Hershey fonts are ASCII only: anything else (UTF-8 in view names) would be
// drawn as garbage, so it becomes '?'.
std::string Printable(const std::string& text) {
  std::string out;
  out.reserve(text.size());
  for (const char c : text) {
    const unsigned char u = static_cast<unsigned char>(c);
    if (u == '\n' || u == '\t' || u == '\r') {
      out += ' ';
    } else if (u < 32 || u >= 127) {
      out += '?';
    } else {
      out += c;
    }
  }
  return out;
}

std::string Format(const char* format, double value) {
  char buffer[64];
  std::snprintf(buffer, sizeof(buffer), format, value);
  return buffer;
}

// Compact number for labels: 4 significant digits, no exponent for the
// magnitudes scales usually have.
std::string FormatValue(double value) {
  if (!Finite(value)) return "n/a";
  const double a = std::abs(value);
  if (a != 0 && (a < 1e-3 || a >= 1e6)) return Format("%.3g", value);
  return Format("%.4g", value);
}

cv::Size TextSize(const std::string& text, double scale, int thickness) {
  int baseline = 0;
  return cv::getTextSize(text, kFont, scale, thickness, &baseline);
}

enum class Align { kLeft, kCenter, kRight };

// `anchor` is the baseline point at the left edge, centre or right edge.
void PutText(cv::Mat& canvas,
             const std::string& text,
             cv::Point anchor,
             double scale,
             const cv::Scalar& colour,
             int thickness = 1,
             Align align = Align::kLeft) {
  const std::string printable = Printable(text);
  const cv::Size size = TextSize(printable, scale, thickness);
  if (align == Align::kCenter) anchor.x -= size.width / 2;
  if (align == Align::kRight) anchor.x -= size.width;
  cv::putText(
      canvas, printable, anchor, kFont, scale, colour, thickness, cv::LINE_AA);
}

// Shortens `text` with "..." until it fits `max_width` px.
std::string Ellipsize(const std::string& text,
                      double scale,
                      int thickness,
                      int max_width) {
  std::string out = Printable(text);
  if (TextSize(out, scale, thickness).width <= max_width) return out;
  while (!out.empty() &&
         TextSize(out + "...", scale, thickness).width > max_width) {
    out.pop_back();
  }
  return out + "...";
}

// Greedy word wrap to `max_width` px; at most `max_lines` lines (the last one
// ellipsized), because a long failure reason must not run off the picture.
std::vector<std::string> WrapText(const std::string& text,
                                  double scale,
                                  int thickness,
                                  int max_width,
                                  int max_lines) {
  std::vector<std::string> words;
  std::istringstream stream(Printable(text));
  std::string word;
  while (stream >> word) words.push_back(word);
  std::vector<std::string> lines;
  std::string line;
  for (size_t i = 0; i < words.size(); ++i) {
    const std::string candidate =
        line.empty() ? words[i] : line + " " + words[i];
    if (line.empty() ||
        TextSize(candidate, scale, thickness).width <= max_width) {
      line = candidate;
      continue;
    }
    lines.push_back(line);
    line = words[i];
  }
  if (!line.empty()) lines.push_back(line);
  if (static_cast<int>(lines.size()) > max_lines) {
    std::string last = lines[max_lines - 1];
    for (size_t i = max_lines; i < lines.size(); ++i) last += " " + lines[i];
    lines.resize(max_lines);
    lines.back() = last;
  }
  for (std::string& l : lines) l = Ellipsize(l, scale, thickness, max_width);
  return lines;
}

// Draws wrapped text from baseline y; returns the baseline after the last
// line.
int PutWrapped(cv::Mat& canvas,
               const std::string& text,
               int x,
               int y,
               int max_width,
               int max_lines,
               double scale,
               const cv::Scalar& colour,
               int thickness = 1,
               int line_height = 0) {
  if (line_height <= 0) {
    line_height = TextSize("Ag", scale, thickness).height * 17 / 10;
  }
  const std::vector<std::string> lines =
      WrapText(text, scale, thickness, max_width, max_lines);
  for (const std::string& line : lines) {
    PutText(canvas, line, {x, y}, scale, colour, thickness);
    y += line_height;
  }
  return y;
}

// Text rotated by 90 degrees (reading upwards) centred on `centre`: OpenCV
// cannot rotate text, so it is drawn flat and the patch rotated.
void PutVerticalText(cv::Mat& canvas,
                     const std::string& text,
                     cv::Point centre,
                     double scale,
                     const cv::Scalar& colour,
                     int thickness = 1) {
  const std::string printable = Printable(text);
  int baseline = 0;
  const cv::Size size =
      cv::getTextSize(printable, kFont, scale, thickness, &baseline);
  cv::Mat flat(size.height + baseline + 4, size.width + 4, CV_8UC3, kWhite);
  cv::putText(flat,
              printable,
              {2, size.height + 2},
              kFont,
              scale,
              colour,
              thickness,
              cv::LINE_AA);
  cv::Mat rotated;
  cv::rotate(flat, rotated, cv::ROTATE_90_COUNTERCLOCKWISE);
  cv::Rect target(centre.x - rotated.cols / 2,
                  centre.y - rotated.rows / 2,
                  rotated.cols,
                  rotated.rows);
  const cv::Rect clipped = target & cv::Rect(0, 0, canvas.cols, canvas.rows);
  if (clipped.area() <= 0) return;
  // Darken-only blend: the patch's white background leaves the canvas as is.
  cv::Mat destination = canvas(clipped);
  cv::Mat source = rotated(cv::Rect(clipped.x - target.x,
                                    clipped.y - target.y,
                                    clipped.width,
                                    clipped.height));
  cv::min(destination, source, destination);
}

// ------------------------------------------------------------ Geometry ---

cv::Point Fixed(const cv::Point2d& p) {
  return cv::Point(static_cast<int>(std::lround(p.x * kShiftScale)),
                   static_cast<int>(std::lround(p.y * kShiftScale)));
}

// Liang-Barsky clipping of segment a-b to `box`; false if nothing is left.
// Needed before the fixed-point conversion: a line to a far-away point would
// overflow int.
bool ClipSegment(const cv::Rect2d& box, cv::Point2d* a, cv::Point2d* b) {
  if (!Finite(a->x) || !Finite(a->y) || !Finite(b->x) || !Finite(b->y)) {
    return false;
  }
  const double dx = b->x - a->x, dy = b->y - a->y;
  double t0 = 0, t1 = 1;
  const double p[4] = {-dx, dx, -dy, dy};
  const double q[4] = {a->x - box.x,
                       box.x + box.width - a->x,
                       a->y - box.y,
                       box.y + box.height - a->y};
  for (int i = 0; i < 4; ++i) {
    if (p[i] == 0) {
      if (q[i] < 0) return false;
      continue;
    }
    const double t = q[i] / p[i];
    if (p[i] < 0) {
      t0 = std::max(t0, t);
    } else {
      t1 = std::min(t1, t);
    }
    if (t0 > t1) return false;
  }
  const cv::Point2d start = *a;
  *a = start + t0 * cv::Point2d(dx, dy);
  *b = start + t1 * cv::Point2d(dx, dy);
  return true;
}

void DrawSegment(cv::Mat& image,
                 cv::Point2d a,
                 cv::Point2d b,
                 const cv::Scalar& colour,
                 int thickness,
                 bool dashed = false) {
  const cv::Rect2d box(-4, -4, image.cols + 8, image.rows + 8);
  if (!ClipSegment(box, &a, &b)) return;
  if (!dashed) {
    cv::line(image, Fixed(a), Fixed(b), colour, thickness, cv::LINE_AA, kShift);
    return;
  }
  const double length = cv::norm(b - a);
  if (length <= 0) return;
  const double dash = 9, gap = 6;
  const cv::Point2d u = (b - a) * (1.0 / length);
  for (double t = 0; t < length; t += dash + gap) {
    const double end = std::min(t + dash, length);
    cv::line(image,
             Fixed(a + u * t),
             Fixed(a + u * end),
             colour,
             thickness,
             cv::LINE_AA,
             kShift);
  }
}

void DrawDot(cv::Mat& image,
             const cv::Point2d& centre,
             double radius,
             const cv::Scalar& colour,
             int thickness = cv::FILLED) {
  if (!Finite(centre.x) || !Finite(centre.y)) return;
  if (centre.x < -50 || centre.y < -50 || centre.x > image.cols + 50 ||
      centre.y > image.rows + 50) {
    return;
  }
  cv::circle(image,
             Fixed(centre),
             static_cast<int>(radius * kShiftScale),
             colour,
             thickness,
             cv::LINE_AA,
             kShift);
}

void DrawDiamond(cv::Mat& image,
                 const cv::Point2d& c,
                 double r,
                 const cv::Scalar& fill,
                 const cv::Scalar& edge) {
  if (!Finite(c.x) || !Finite(c.y)) return;
  std::vector<cv::Point> points = {Fixed({c.x, c.y - r}),
                                   Fixed({c.x + r, c.y}),
                                   Fixed({c.x, c.y + r}),
                                   Fixed({c.x - r, c.y})};
  cv::fillConvexPoly(image, points, fill, cv::LINE_AA, kShift);
  cv::polylines(image, points, true, edge, 1, cv::LINE_AA, kShift);
}

// --------------------------------------------------------------- Ranges ---

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

// Axis range for data that may hold a few wild values (a blur estimate at
// 1e300, a depth near zero): the 1st-99th percentile range widened by half
// its span, never beyond the data, so ordinary tails stay on the axes.
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

// Ticks at 1, 2 or 5 times a power of ten, about `target` of them.
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
              bool y_ticks_shown = true) {
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

// Blank plot area (white over the grid) with a centred message.
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

// ------------------------------------------------------------- Legends ---

enum class Glyph {
  kDot,
  kLine,
  kDashedLine,
  kLineAndDot,
  kBand,
  kDiamond,
  kFilledSquare,
  kOutlineSquare
};

struct LegendEntry {
  std::string label;
  cv::Scalar colour;
  Glyph glyph;
};

void DrawGlyph(cv::Mat& canvas,
               const LegendEntry& entry,
               const cv::Point2d& left_middle) {
  const cv::Point2d a = left_middle, b = left_middle + cv::Point2d(26, 0);
  const cv::Point2d mid = left_middle + cv::Point2d(13, 0);
  switch (entry.glyph) {
    case Glyph::kDot:
      DrawDot(canvas, mid, 4, entry.colour);
      break;
    case Glyph::kLine:
      DrawSegment(canvas, a, b, entry.colour, 2);
      break;
    case Glyph::kDashedLine:
      DrawSegment(canvas, a, b, entry.colour, 2, true);
      break;
    case Glyph::kLineAndDot:
      DrawSegment(canvas, a, b, entry.colour, 2);
      DrawDot(canvas, mid, 4, entry.colour);
      break;
    case Glyph::kBand:
      cv::rectangle(
          canvas,
          cv::Rect(static_cast<int>(a.x), static_cast<int>(a.y) - 7, 26, 14),
          entry.colour,
          cv::FILLED);
      break;
    case Glyph::kDiamond:
      DrawDiamond(canvas, mid, 7, entry.colour, cv::Scalar(0, 0, 0));
      break;
    case Glyph::kFilledSquare:
    case Glyph::kOutlineSquare: {
      const cv::Rect square(
          static_cast<int>(mid.x) - 8, static_cast<int>(mid.y) - 8, 16, 16);
      if (entry.glyph == Glyph::kFilledSquare) {
        cv::rectangle(canvas, square, entry.colour, cv::FILLED);
        cv::rectangle(canvas, square, cv::Scalar(0, 0, 0), 1);
      } else {
        cv::rectangle(canvas, square, entry.colour, 1);
      }
      break;
    }
  }
}

// A boxed vertical legend with its top-left corner at `origin`.
cv::Rect LegendBox(const std::vector<LegendEntry>& entries,
                   const cv::Point& origin) {
  int width = 0;
  for (const LegendEntry& e : entries) {
    width = std::max(width, TextSize(Printable(e.label), 0.48, 1).width);
  }
  return cv::Rect(origin.x,
                  origin.y,
                  width + 58,
                  static_cast<int>(entries.size()) * 24 + 10);
}

void DrawLegend(cv::Mat& canvas,
                const std::vector<LegendEntry>& entries,
                const cv::Rect& box) {
  cv::rectangle(canvas, box, kWhite, cv::FILLED);
  cv::rectangle(canvas, box, cv::Scalar(180, 180, 180), 1);
  int y = box.y + 17;
  for (const LegendEntry& e : entries) {
    DrawGlyph(canvas, e, cv::Point2d(box.x + 10, y));
    PutText(canvas, e.label, {box.x + 46, y + 5}, 0.48, kTextColour);
    y += 24;
  }
}

// Title (bold) and optional subtitle lines at the top; a failed estimate puts
// its reason first, in red, because that is what a reader must see first.
// Text stays above `bottom` (lines that would not fit are dropped, the last
// kept line of each block ellipsized).
int DrawHeader(cv::Mat& canvas,
               const DPScaleResult& result,
               const std::string& title,
               const std::string& subtitle,
               int bottom) {
  const int width = canvas.cols - 40;
  const int kBold = 26, kThin = 20;
  int y = 30;
  // Lines `line` px apart that fit from baseline y (descenders need ~6 px),
  // keeping `reserve` px for later blocks; at least one.
  auto fit = [&](int line, int reserve, int wanted) {
    const int room = (bottom - reserve - 6 - y) / line + 1;
    return std::max(1, std::min(wanted, room));
  };
  const int subtitle_room = subtitle.empty() ? 0 : kThin;
  if (!result.success) {
    const std::string reason = result.failure_reason.empty()
                                   ? std::string("no reason given")
                                   : result.failure_reason;
    y = PutWrapped(canvas,
                   "Estimate failed: " + reason,
                   20,
                   y,
                   width,
                   fit(kBold, kBold + subtitle_room, 2),
                   0.62,
                   kFailureColour,
                   2,
                   kBold);
  }
  y = PutWrapped(canvas,
                 title,
                 20,
                 y,
                 width,
                 fit(kBold, subtitle_room, 2),
                 0.62,
                 kTextColour,
                 2,
                 kBold);
  if (!subtitle.empty() && y - 4 + 6 <= bottom) {
    y -= 4;
    y = PutWrapped(canvas,
                   subtitle,
                   20,
                   y,
                   width,
                   fit(kThin, 0, 2),
                   0.48,
                   kMutedText,
                   1,
                   kThin);
  }
  return y;
}

// ------------------------------------------------------ Diverging map ---

// ColorBrewer RdBu (11 classes) from blue to red, as BGR.
const cv::Scalar kDiverging[] = {{97, 48, 5},
                                 {172, 102, 33},
                                 {195, 147, 67},
                                 {222, 197, 146},
                                 {240, 229, 209},
                                 {247, 247, 247},
                                 {199, 219, 253},
                                 {130, 165, 244},
                                 {77, 96, 214},
                                 {43, 24, 178},
                                 {31, 0, 103}};
constexpr int kNumDiverging = 11;

// t in [-1, 1]: -1 = deep blue, 0 = near white, +1 = deep red.
cv::Scalar DivergingColour(double t) {
  if (!Finite(t)) return cv::Scalar(150, 150, 150);
  const double u = (Clamp(t, -1, 1) + 1) / 2 * (kNumDiverging - 1);
  const int i = std::min(static_cast<int>(u), kNumDiverging - 2);
  const double f = u - i;
  return kDiverging[i] * (1 - f) + kDiverging[i + 1] * f;
}

// A round number at or above v for the colour bar limit, in steps fine
// enough (1, 1.5, 2, ... x 10^k) that the colours stay saturated.
double NiceCeil(double v) {
  if (!(v > 0) || !Finite(v)) return 1;
  const double magnitude = std::pow(10.0, std::floor(std::log10(v)));
  for (const double m : {1.0, 1.5, 2.0, 2.5, 3.0, 4.0, 5.0, 6.0, 8.0, 10.0}) {
    if (m * magnitude >= v * (1 - 1e-9)) return m * magnitude;
  }
  return 10 * magnitude;
}

// ---------------------------------------------------------- Utilities ---

bool WritePng(const cv::Mat& image, const std::string& path) {
  if (image.empty() || path.empty()) return false;
  try {
    return cv::imwrite(path, image);
  } catch (...) {
    return false;
  }
}

std::string ViewName(const DPScaleResult& result, int view) {
  if (view >= 0 && view < static_cast<int>(result.views.size()) &&
      !result.views[view].name.empty()) {
    return result.views[view].name;
  }
  return "view " + std::to_string(view);
}

bool ViewUsed(const DPScaleResult& result, int view) {
  return view >= 0 && view < static_cast<int>(result.views.size()) &&
         result.views[view].used;
}

// DP-frame pixels per working-frame pixel of each view, recovered from its
// patches (both radii are stored); NaN where no patch tells.
std::map<int, double> FramePerWorkingPixel(const DPScaleResult& result) {
  std::map<int, std::vector<double>> ratios;
  for (const PatchSample& s : result.patches) {
    if (Finite(s.radius_px) && Finite(s.radius_frame_px) &&
        std::abs(s.radius_px) > 1e-6) {
      const double ratio = s.radius_frame_px / s.radius_px;
      if (ratio > 0 && Finite(ratio)) ratios[s.view].push_back(ratio);
    }
  }
  std::map<int, double> out;
  for (const auto& r : ratios) out[r.first] = FiniteMedian(r.second);
  return out;
}

std::string ScaleText(double scale) { return FormatValue(scale) + " m/unit"; }

}  // namespace

// ============================================================ Blur fit ===

cv::Mat RenderBlurFitPlot(const DPScaleResult& result) {
  cv::Mat canvas(700, 1000, CV_8UC3, kWhite);
  try {
    const std::map<int, double> frame_per_working =
        FramePerWorkingPixel(result);

    // What to show: used patches of used views; if there are none (a failed
    // estimate), the selected ones, so that the reader sees why it failed.
    bool any_used = false;
    for (const PatchSample& s : result.patches) {
      if (s.used && ViewUsed(result, s.view)) any_used = true;
    }
    struct Point {
      int view;
      double inv_depth, measured, predicted;
    };
    std::map<int, std::vector<Point>> by_view;
    for (const PatchSample& s : result.patches) {
      const bool shown =
          any_used ? (s.used && ViewUsed(result, s.view)) : s.selected;
      if (!shown) continue;
      Point p;
      p.view = s.view;
      p.inv_depth = s.depth > 0 && Finite(s.depth) ? 1.0 / s.depth : kNaN;
      p.measured = s.radius_frame_px;
      const auto ratio = frame_per_working.find(s.view);
      p.predicted = ratio != frame_per_working.end()
                        ? s.predicted_radius_px * ratio->second
                        : kNaN;
      if (!Finite(p.measured)) continue;
      by_view[s.view].push_back(p);
    }

    // Colours: the views with the most points get the palette, the rest are
    // grey (drawn underneath) so that more than 10 views stay readable.
    std::vector<std::pair<int, int>> order;  // (-count, view)
    for (const auto& v : by_view) {
      order.emplace_back(-static_cast<int>(v.second.size()), v.first);
    }
    std::sort(order.begin(), order.end());
    std::map<int, cv::Scalar> colour;
    int num_points = 0, num_other_views = 0, num_other_points = 0;
    for (size_t i = 0; i < order.size(); ++i) {
      const int view = order[i].second;
      num_points += -order[i].first;
      if (static_cast<int>(i) < kNumPaletteColours) {
        colour[view] = kPalette[i];
      } else {
        colour[view] = kOtherViewsColour;
        ++num_other_views;
        num_other_points += -order[i].first;
      }
    }

    // Axis ranges that a few wild values cannot squash (see RobustRange);
    // inverse depth first, since the model lines are drawn over it.
    std::vector<double> inv_depths, measured_left, both_right;
    std::vector<double> residuals;
    for (const auto& v : by_view) {
      for (const Point& p : v.second) {
        if (Finite(p.inv_depth)) {
          inv_depths.push_back(p.inv_depth);
          measured_left.push_back(p.measured);
        }
        if (Finite(p.predicted)) {
          residuals.push_back(std::abs(p.measured - p.predicted));
          both_right.push_back(p.measured);
          both_right.push_back(p.predicted);
        }
      }
    }
    const bool have_left = !inv_depths.empty();
    const bool have_right = !residuals.empty();
    const double median_residual = FiniteMedian(residuals);
    Range left_x = RobustRange(inv_depths);
    Range left_y = RobustRange(measured_left);
    Range right_range = RobustRange(both_right);

    // Per-view prediction line: the thin-lens radius is affine in 1/z', so a
    // least-squares line through the core's own predictions reproduces them
    // exactly (and stays what the core computed); without predictions, the
    // lens formula under the final scale.
    struct Line {
      double x0, x1, y0, y1;
    };
    std::map<int, Line> lines;
    for (const auto& v : by_view) {
      Range xr;
      double sx = 0, sy = 0, sxx = 0, sxy = 0;
      int n = 0;
      for (const Point& p : v.second) {
        if (!Finite(p.inv_depth)) continue;
        if (p.inv_depth >= left_x.lo && p.inv_depth <= left_x.hi) {
          xr.Add(p.inv_depth);
        }
        if (!Finite(p.predicted)) continue;
        sx += p.inv_depth;
        sy += p.predicted;
        sxx += p.inv_depth * p.inv_depth;
        sxy += p.inv_depth * p.predicted;
        ++n;
      }
      if (!xr.Valid()) continue;
      const double det = n * sxx - sx * sx;
      double slope = kNaN, intercept = kNaN;
      if (n >= 2 && det > 1e-12 * std::max(1.0, n * sxx)) {
        slope = (n * sxy - sx * sy) / det;
        intercept = (sy - slope * sx) / n;
      } else if (v.first >= 0 &&
                 v.first < static_cast<int>(result.views.size())) {
        const DPViewResult& view = result.views[v.first];
        if (view.lens.Check() && Finite(view.focus_distance_model) &&
            result.scale > 0 && Finite(result.scale)) {
          // r(1/z') at 1/z' = 1 and 2 gives the line.
          const double r1 = PredictBlurRadiusPx(view.lens,
                                                view.lens.PixelPitchMm(),
                                                result.scale,
                                                view.focus_distance_model,
                                                1.0);
          const double r2 = PredictBlurRadiusPx(view.lens,
                                                view.lens.PixelPitchMm(),
                                                result.scale,
                                                view.focus_distance_model,
                                                0.5);
          slope = r2 - r1;
          intercept = r1 - slope;
        }
      }
      if (!Finite(slope) || !Finite(intercept)) continue;
      const double pad = 0.03 * std::max(xr.hi - xr.lo, 1e-12);
      Line line;
      line.x0 = xr.lo - pad;
      line.x1 = xr.hi + pad;
      line.y0 = intercept + slope * line.x0;
      line.y1 = intercept + slope * line.x1;
      lines[v.first] = line;
      left_y.Add(line.y0);
      left_y.Add(line.y1);
    }
    PadRange(&left_x, 0.05);
    PadRange(&left_y, 0.08);
    PadRange(&right_range, 0.06);
    int off_scale = 0;
    for (const auto& v : by_view) {
      for (const Point& p : v.second) {
        const bool left_out =
            Finite(p.inv_depth) &&
            (p.inv_depth < left_x.lo || p.inv_depth > left_x.hi ||
             p.measured < left_y.lo || p.measured > left_y.hi);
        const bool right_out =
            Finite(p.predicted) &&
            (p.predicted < right_range.lo || p.predicted > right_range.hi ||
             p.measured < right_range.lo || p.measured > right_range.hi);
        if (left_out || right_out) ++off_scale;
      }
    }

    // Header.
    std::string title = "Measured blur vs thin-lens model";
    if (have_right) {
      title += ": median |measured - predicted| = " +
               Format("%.3g", median_residual) + " px";
    }
    std::ostringstream subtitle;
    subtitle << num_points << (any_used ? " used" : " selected")
             << " patches in " << by_view.size() << " view"
             << (by_view.size() == 1 ? "" : "s");
    if (!any_used) subtitle << " (no patch was used)";
    if (off_scale > 0) subtitle << ", " << off_scale << " off the axes";
    subtitle << "; radii signed (+ = farther than the focus) in DP-frame "
                "pixels";
    if (Finite(result.scale) && result.scale > 0) {
      subtitle << "; model under the final s = " << ScaleText(result.scale);
    }

    // Panels (plot areas) below the header, which takes more room for a
    // failure.
    const int top = result.success ? 108 : 150;
    DrawHeader(canvas, result, title, subtitle.str(), top - 28);
    const int height = 520 - top;
    Axes left;
    left.area = cv::Rect(95, top, 385, height);
    left.x = left_x;
    left.y = left_y;
    Axes right;
    right.area = cv::Rect(590, top, 385, height);
    right.x = right_range;
    right.y = right_range;

    PutText(canvas,
            "blur against inverse depth; lines: model",
            {left.area.x, top - 10},
            0.5,
            kTextColour,
            1);
    PutText(canvas,
            "blur against the model's prediction",
            {right.area.x, top - 10},
            0.5,
            kTextColour,
            1);
    DrawAxes(canvas,
             left,
             "inverse depth 1/z' (1 / model unit)",
             "measured blur radius (px)");
    DrawAxes(canvas,
             right,
             "predicted blur radius (px)",
             "measured blur radius (px)");

    cv::Mat left_roi = left.Roi(canvas);
    cv::Mat right_roi = right.Roi(canvas);
    // The focal plane (r = 0) as a reference in the left panel.
    if (left.y.lo < 0 && left.y.hi > 0) {
      DrawSegment(left_roi,
                  left.ToLocal(left.x.lo, 0),
                  left.ToLocal(left.x.hi, 0),
                  cv::Scalar(160, 160, 160),
                  1,
                  true);
    }
    if (have_right) {
      DrawSegment(right_roi,
                  right.ToLocal(right.x.lo, right.x.lo),
                  right.ToLocal(right.x.hi, right.x.hi),
                  cv::Scalar(0, 0, 0),
                  1);
    }
    // Model lines under the points: the points are the evidence.
    for (auto it = order.rbegin(); it != order.rend(); ++it) {
      const auto line = lines.find(it->second);
      if (line == lines.end()) continue;
      DrawSegment(left_roi,
                  left.ToLocal(line->second.x0, line->second.y0),
                  left.ToLocal(line->second.x1, line->second.y1),
                  colour[it->second],
                  2);
    }
    // Grey views first, then the coloured ones from the smallest so that the
    // largest view does not hide the others.
    for (int pass = 0; pass < 2; ++pass) {
      for (auto it = order.rbegin(); it != order.rend(); ++it) {
        const int view = it->second;
        const bool grey = colour[view] == kOtherViewsColour;
        if (grey != (pass == 0)) continue;
        for (const Point& p : by_view[view]) {
          if (Finite(p.inv_depth)) {
            DrawDot(left_roi,
                    left.ToLocal(p.inv_depth, p.measured),
                    2.8,
                    colour[view]);
          }
          if (Finite(p.predicted)) {
            DrawDot(right_roi,
                    right.ToLocal(p.predicted, p.measured),
                    2.8,
                    colour[view]);
          }
        }
      }
    }
    cv::rectangle(canvas, left.area, kAxisColour, 1);
    cv::rectangle(canvas, right.area, kAxisColour, 1);
    if (!have_left) DrawNoData(canvas, left.area, "no patch with a depth");
    if (!have_right) {
      DrawNoData(canvas,
                 right.area,
                 "no predicted radii (no scale or focus distances)");
    }

    // Legend under the panels.
    std::vector<LegendEntry> entries;
    for (size_t i = 0; i < order.size() && i < kNumPaletteColours; ++i) {
      const int view = order[i].second;
      entries.push_back({ViewName(result, view) + " (" +
                             std::to_string(-order[i].first) + ")",
                         colour[view],
                         Glyph::kLineAndDot});
    }
    if (num_other_views > 0) {
      entries.push_back({std::to_string(num_other_views) + " more views (" +
                             std::to_string(num_other_points) + ")",
                         kOtherViewsColour,
                         Glyph::kDot});
    }
    if (have_right) {
      entries.push_back(
          {"y = x (perfect fit)", cv::Scalar(0, 0, 0), Glyph::kLine});
    }
    const int columns = 4, column_width = (canvas.cols - 60) / columns;
    const int legend_top = 614;
    for (size_t i = 0; i < entries.size(); ++i) {
      const int x = 30 + static_cast<int>(i % columns) * column_width;
      const int y = legend_top + static_cast<int>(i / columns) * 25;
      DrawGlyph(canvas, entries[i], cv::Point2d(x, y));
      PutText(canvas,
              Ellipsize(entries[i].label, 0.45, 1, column_width - 42),
              {x + 34, y + 5},
              0.45,
              kTextColour);
    }
    if (entries.empty()) {
      PutText(
          canvas, "no patches to show", {30, legend_top + 5}, 0.5, kMutedText);
    } else {
      PutText(canvas,
              "view (number of patches):",
              {30, legend_top - 21},
              0.45,
              kMutedText);
    }
  } catch (...) {
    // Whatever was drawn so far is still worth showing.
  }
  return canvas;
}

bool WriteBlurFitPlot(const DPScaleResult& result, const std::string& path) {
  try {
    return WritePng(RenderBlurFitPlot(result), path);
  } catch (...) {
    return false;
  }
}

// ========================================================== Loss curve ===

cv::Mat RenderLossCurvePlot(const DPScaleResult& result) {
  cv::Mat canvas(700, 1000, CV_8UC3, kWhite);
  try {
    // Curve sorted by scale (the core sorts it, but the picture must not
    // depend on that), finite points only.
    std::vector<std::pair<double, double>> curve;
    const size_t n = std::min(result.candidate_scales.size(),
                              result.candidate_losses.size());
    for (size_t i = 0; i < n; ++i) {
      if (Finite(result.candidate_scales[i]) &&
          Finite(result.candidate_losses[i])) {
        curve.emplace_back(result.candidate_scales[i],
                           result.candidate_losses[i]);
      }
    }
    std::sort(curve.begin(), curve.end());
    const bool have_curve = !curve.empty();

    const bool have_final = result.success && Finite(result.scale);
    const bool have_ci = have_final && Finite(result.scale_ci_low) &&
                         Finite(result.scale_ci_high) &&
                         result.scale_ci_high >= result.scale_ci_low;
    const bool have_linear =
        Finite(result.scale_initial) && result.scale_initial != 0;
    const bool have_minimum = have_curve && Finite(result.scale_intensity) &&
                              result.scale_intensity != 0;
    const bool have_intensity_ci =
        have_minimum && Finite(result.intensity_ci_low) &&
        Finite(result.intensity_ci_high) &&
        result.intensity_ci_high >= result.intensity_ci_low;

    Range x_range, y_range;
    for (const auto& p : curve) {
      x_range.Add(p.first);
      y_range.Add(p.second);
    }
    if (have_linear) x_range.Add(result.scale_initial);
    if (have_final) x_range.Add(result.scale);
    if (have_ci) {
      x_range.Add(result.scale_ci_low);
      x_range.Add(result.scale_ci_high);
    }
    if (have_minimum) x_range.Add(result.scale_intensity);
    const bool have_x = x_range.Valid();
    // Without a curve only a few vertical lines are left: wider margins keep
    // them from filling the panel.
    PadRange(&x_range, have_curve ? 0.03 : 0.5);
    PadRange(&y_range, 0.08);
    // Headroom above the curve for the legend (its ends rise highest).
    if (have_curve) {
      y_range.hi = y_range.lo + (y_range.hi - y_range.lo) / 0.7;
    }

    // Header.
    std::string title = "Intensity loss over candidate scales";
    if (!result.intensity_loss.empty()) {
      title += " (loss: " + result.intensity_loss + ")";
    }
    std::ostringstream subtitle;
    if (have_final) {
      subtitle << "final s = " << ScaleText(result.scale);
      if (have_ci) {
        subtitle << ", interval [" << FormatValue(result.scale_ci_low) << ", "
                 << FormatValue(result.scale_ci_high) << "]";
      }
      subtitle << (result.intensity_used ? " (intensity stage adopted)"
                                         : " (linear estimate kept)");
    } else if (have_linear) {
      subtitle << "linear estimate s* = " << ScaleText(result.scale_initial);
    }
    Axes axes;
    const int top = result.success ? 100 : 140;
    DrawHeader(canvas, result, title, subtitle.str(), top - 12);
    axes.area = cv::Rect(105, top, 860, 530 - top);
    axes.x = x_range;
    axes.y = y_range;
    cv::Mat roi = axes.Roi(canvas);

    // Band first, so that grid and curve are drawn over it.
    const cv::Scalar band_colour(250, 228, 205);
    if (have_ci) {
      const double a = axes.ToPixel(result.scale_ci_low, 0).x;
      const double b = axes.ToPixel(result.scale_ci_high, 0).x;
      const int x0 = static_cast<int>(std::floor(std::min(a, b)));
      const int x1 =
          std::max(x0 + 2, static_cast<int>(std::ceil(std::max(a, b))));
      const cv::Rect band =
          cv::Rect(x0, axes.area.y, x1 - x0, axes.area.height) & axes.area;
      if (band.area() > 0) canvas(band).setTo(band_colour);
    }
    DrawAxes(canvas,
             axes,
             "scale s (metres per model unit)",
             have_curve ? "loss" : "",
             have_x,
             have_curve);
    if (have_ci) {
      const double a = axes.ToPixel(result.scale_ci_low, 0).x;
      const double b = axes.ToPixel(result.scale_ci_high, 0).x;
      DrawSegment(roi,
                  {a - axes.area.x, 0.0},
                  {a - axes.area.x, double(axes.area.height)},
                  cv::Scalar(230, 190, 150),
                  1);
      DrawSegment(roi,
                  {b - axes.area.x, 0.0},
                  {b - axes.area.x, double(axes.area.height)},
                  cv::Scalar(230, 190, 150),
                  1);
    }

    const cv::Scalar curve_colour(60, 60, 60);
    const cv::Scalar final_colour(170, 90, 20);
    const cv::Scalar linear_colour(20, 130, 250);
    const cv::Scalar minimum_colour(50, 40, 215);
    const double h = axes.area.height;
    if (have_final) {
      const double x = axes.ToLocal(result.scale, 0).x;
      DrawSegment(roi, {x, 0.0}, {x, h}, final_colour, 2);
    }
    if (have_linear) {
      const double x = axes.ToLocal(result.scale_initial, 0).x;
      DrawSegment(roi, {x, 0.0}, {x, h}, linear_colour, 2, true);
    }
    for (size_t i = 0; i + 1 < curve.size(); ++i) {
      DrawSegment(roi,
                  axes.ToLocal(curve[i].first, curve[i].second),
                  axes.ToLocal(curve[i + 1].first, curve[i + 1].second),
                  curve_colour,
                  2);
    }
    // Candidate dots only where they are far enough apart to be seen as
    // such; denser ones would just make the line lumpy.
    if (curve.size() * 12 <= static_cast<size_t>(axes.area.width)) {
      for (const auto& p : curve) {
        DrawDot(roi, axes.ToLocal(p.first, p.second), 2.2, curve_colour);
      }
    }

    // The minimiser at the curve's height (linear interpolation; the core
    // refines the minimum between candidates).
    double minimum_loss = kNaN;
    if (have_minimum) {
      const double s = result.scale_intensity;
      if (s <= curve.front().first) {
        minimum_loss = curve.front().second;
      } else if (s >= curve.back().first) {
        minimum_loss = curve.back().second;
      } else {
        for (size_t i = 0; i + 1 < curve.size(); ++i) {
          if (s >= curve[i].first && s <= curve[i + 1].first) {
            const double span = curve[i + 1].first - curve[i].first;
            const double f = span > 0 ? (s - curve[i].first) / span : 0;
            minimum_loss =
                curve[i].second + f * (curve[i + 1].second - curve[i].second);
            break;
          }
        }
      }
      const cv::Point2d m = axes.ToLocal(s, minimum_loss);
      if (have_intensity_ci) {
        const double a = axes.ToLocal(result.intensity_ci_low, 0).x;
        const double b = axes.ToLocal(result.intensity_ci_high, 0).x;
        DrawSegment(roi, {a, m.y}, {b, m.y}, minimum_colour, 2);
        DrawSegment(roi, {a, m.y - 7}, {a, m.y + 7}, minimum_colour, 2);
        DrawSegment(roi, {b, m.y - 7}, {b, m.y + 7}, minimum_colour, 2);
      }
      DrawDiamond(roi, m, 8, minimum_colour, cv::Scalar(0, 0, 0));
    }
    cv::rectangle(canvas, axes.area, kAxisColour, 1);

    if (!have_curve) {
      std::string message = "No intensity loss curve: ";
      message += result.intensity_status.empty()
                     ? std::string("the intensity stage was skipped")
                     : result.intensity_status;
      if (!have_x) message += " (and no scale to show)";
      const cv::Rect box(axes.area.x + axes.area.width / 2 - 300,
                         axes.area.y + axes.area.height / 2 - 50,
                         600,
                         100);
      cv::rectangle(canvas, box, cv::Scalar(245, 245, 245), cv::FILLED);
      cv::rectangle(canvas, box, cv::Scalar(180, 180, 180), 1);
      DrawNoData(canvas, box, message);
    }

    // Legend in the corner of the plot area where the curve is least.
    std::vector<LegendEntry> entries;
    if (have_curve) {
      entries.push_back(
          {"loss (" + std::to_string(curve.size()) + " candidate scales)",
           curve_colour,
           Glyph::kLineAndDot});
    }
    if (have_minimum) {
      entries.push_back(
          {"loss minimum s = " + FormatValue(result.scale_intensity) +
               (have_intensity_ci ? " (bar: its interval)" : ""),
           minimum_colour,
           Glyph::kDiamond});
    }
    if (have_linear) {
      entries.push_back(
          {"linear estimate s* = " + FormatValue(result.scale_initial),
           linear_colour,
           Glyph::kDashedLine});
    }
    if (have_final) {
      entries.push_back({"final s = " + FormatValue(result.scale),
                         final_colour,
                         Glyph::kLine});
    }
    if (have_ci) {
      entries.push_back({"final interval [" + FormatValue(result.scale_ci_low) +
                             ", " + FormatValue(result.scale_ci_high) + "]",
                         band_colour,
                         Glyph::kBand});
    }
    if (!entries.empty()) {
      cv::Rect box = LegendBox(entries, {0, 0});
      const cv::Rect& a = axes.area;
      const std::vector<cv::Point> corners = {
          {a.x + a.width - box.width - 10, a.y + 10},
          {a.x + 10, a.y + 10},
          {a.x + a.width - box.width - 10, a.y + a.height - box.height - 10},
          {a.x + 10, a.y + a.height - box.height - 10}};
      int best = 0, best_count = std::numeric_limits<int>::max();
      for (size_t c = 0; c < corners.size(); ++c) {
        const cv::Rect candidate(corners[c], box.size());
        int count = 0;
        for (const auto& p : curve) {
          if (candidate.contains(axes.ToPixel(p.first, p.second))) ++count;
        }
        if (have_minimum && candidate.contains(axes.ToPixel(
                                result.scale_intensity, minimum_loss))) {
          count += 1000;
        }
        if (count < best_count) {
          best_count = count;
          best = static_cast<int>(c);
        }
      }
      box = cv::Rect(corners[best], box.size());
      DrawLegend(canvas, entries, box);
    }

    // Status of the intensity stage, in words.
    std::string status = result.intensity_used
                             ? "Intensity stage (adopted): "
                             : "Intensity stage (not adopted): ";
    status += result.intensity_status.empty() ? std::string("no status")
                                              : result.intensity_status;
    if (have_minimum && Finite(result.intensity_bootstrap_support)) {
      status += " (bootstrap support " +
                Format("%.0f", 100 * result.intensity_bootstrap_support) +
                " %)";
    }
    PutWrapped(
        canvas, status, 30, 608, canvas.cols - 60, 3, 0.52, kTextColour, 1, 24);
  } catch (...) {
    // Keep what was drawn.
  }
  return canvas;
}

bool WriteLossCurvePlot(const DPScaleResult& result, const std::string& path) {
  try {
    return WritePng(RenderLossCurvePlot(result), path);
  } catch (...) {
    return false;
  }
}

// ======================================================= Patch overlay ===

namespace {

constexpr int kOverlayMarginX = 10;
constexpr int kOverlayHeader = 96;
constexpr int kOverlayRightPanel = 190;
constexpr int kOverlayFooter = 66;
constexpr int kOverlayMaxWidth = 1600;
constexpr int kOverlayMinWidth = 640;

// Display scale of an image in the overlay: at most 1600 px on either side
// (DP frames can be 6720 px wide), small images enlarged so that the title
// and the patches stay legible.
double OverlayScale(const cv::Size& size) {
  if (size.width <= 0 || size.height <= 0) return 1;
  double d = std::min({1.0,
                       double(kOverlayMaxWidth) / size.width,
                       double(kOverlayMaxWidth) / size.height});
  if (size.width * d < kOverlayMinWidth) {
    d = std::min(double(kOverlayMinWidth) / size.width,
                 double(kOverlayMaxWidth) / size.height);
  }
  return d;
}

// Grey display image: the DP frame is linear and often dark, so it is
// normalised to its 99.5th percentile and gamma-encoded; the contrast is then
// compressed a little so that both white and black squares stand out.
cv::Mat DisplayImage(const cv::Mat& image, const cv::Size& display_size) {
  cv::Mat grey;
  if (image.channels() == 3) {
    cv::cvtColor(image, grey, cv::COLOR_BGR2GRAY);
  } else if (image.channels() == 4) {
    cv::cvtColor(image, grey, cv::COLOR_BGRA2GRAY);
  } else if (image.channels() == 1) {
    grey = image;
  } else {
    cv::extractChannel(image, grey, 0);
  }
  double unit = 1;
  switch (grey.depth()) {
    case CV_8U:
      unit = 1.0 / 255;
      break;
    case CV_16U:
      unit = 1.0 / 65535;
      break;
    default:
      break;
  }
  cv::Mat value;
  grey.convertTo(value, CV_32F, unit);
  cv::patchNaNs(value, 0);
  // Infinities would survive patchNaNs and spoil the white point.
  cv::max(cv::min(value, 1e6), -1e6, value);
  cv::Mat resized;
  const double d = double(display_size.width) / image.cols;
  cv::resize(value,
             resized,
             display_size,
             0,
             0,
             d < 1 ? cv::INTER_AREA : cv::INTER_LINEAR);
  std::vector<double> samples;
  samples.reserve(resized.total() / 4 + 1);
  for (int y = 0; y < resized.rows; y += 2) {
    const float* row = resized.ptr<float>(y);
    for (int x = 0; x < resized.cols; x += 2) samples.push_back(row[x]);
  }
  double white = NearestRankQuantile(samples, 0.995);
  if (!(white > 0)) white = 1;
  cv::Mat normalised = resized * (1.0 / white);
  cv::max(cv::min(normalised, 1.0), 0.0, normalised);
  cv::pow(normalised, 1 / 2.2, normalised);
  cv::Mat display;
  normalised.convertTo(display, CV_8U, 255 * 0.84, 255 * 0.08);
  cv::Mat bgr;
  cv::cvtColor(display, bgr, cv::COLOR_GRAY2BGR);
  return bgr;
}

}  // namespace

cv::Point2d PatchOverlayPoint(const cv::Size& image_size, double x, double y) {
  const double d = OverlayScale(image_size);
  return {kOverlayMarginX + (x + 0.5) * d - 0.5,
          kOverlayHeader + (y + 0.5) * d - 0.5};
}

cv::Mat RenderPatchOverlay(const cv::Mat& image,
                           const std::string& view_name,
                           int view_index,
                           const DPScaleResult& result,
                           double patch_size_px) {
  if (image.empty() || image.cols <= 0 || image.rows <= 0) return cv::Mat();
  const double d = OverlayScale(image.size());
  const cv::Size display_size(
      std::max(1, static_cast<int>(std::lround(image.cols * d))),
      std::max(1, static_cast<int>(std::lround(image.rows * d))));
  const int width = kOverlayMarginX + display_size.width + kOverlayRightPanel;
  const int height =
      kOverlayHeader + std::max(display_size.height, 420) + kOverlayFooter;
  cv::Mat canvas(height, width, CV_8UC3, kWhite);
  try {
    const cv::Rect image_rect(kOverlayMarginX,
                              kOverlayHeader,
                              display_size.width,
                              display_size.height);
    try {
      DisplayImage(image, display_size).copyTo(canvas(image_rect));
    } catch (...) {
      canvas(image_rect).setTo(cv::Scalar(128, 128, 128));
    }
    cv::rectangle(canvas, image_rect, kAxisColour, 1);

    if (!(patch_size_px > 0) || !Finite(patch_size_px)) {
      try {
        const PatchGeometry geometry = DefaultPatchGeometry(image.size());
        patch_size_px = geometry.patch_size / geometry.resize_factor;
      } catch (...) {
        patch_size_px = 0;
      }
      if (!(patch_size_px > 0) || !Finite(patch_size_px)) {
        patch_size_px = 0.03 * std::max(image.cols, image.rows);
      }
    }
    const double half = std::max(2.0, 0.5 * patch_size_px * d);

    std::vector<const PatchSample*> patches;
    std::vector<double> magnitudes;
    int num_used = 0;
    for (const PatchSample& s : result.patches) {
      if (s.view != view_index || !s.selected) continue;
      if (!Finite(s.x) || !Finite(s.y)) continue;
      patches.push_back(&s);
      magnitudes.push_back(std::abs(s.radius_frame_px));
      if (s.used) ++num_used;
    }
    // Colour limit: a round number just above the 98th percentile of |r|, so
    // one wild patch does not wash out the rest.
    const double limit =
        NiceCeil(std::max(NearestRankQuantile(magnitudes, 0.98), 0.1));
    // Unused patches first (underneath), then used ones by confidence so the
    // most trusted are on top.
    std::stable_sort(patches.begin(),
                     patches.end(),
                     [](const PatchSample* a, const PatchSample* b) {
                       if (a->used != b->used) return !a->used;
                       return a->confidence < b->confidence;
                     });

    cv::Mat image_area = canvas(image_rect);
    auto square = [&](const PatchSample& s) {
      const cv::Point2d c = PatchOverlayPoint(image.size(), s.x, s.y) -
                            cv::Point2d(image_rect.x, image_rect.y);
      return cv::Rect2d(c.x - half, c.y - half, 2 * half, 2 * half);
    };
    auto colour_of = [&](const PatchSample& s) {
      return DivergingColour(s.radius_frame_px / limit);
    };
    // Selected-but-unused patches: thin outlines (a dark rim outside the
    // colour keeps near-white ones visible), under the used ones.
    for (const PatchSample* s : patches) {
      if (s->used) continue;
      const cv::Rect2d r = square(*s);
      if (std::abs(r.x) > 1e6 || std::abs(r.y) > 1e6) continue;
      const cv::Scalar colour = colour_of(*s);
      cv::rectangle(image_area,
                    Fixed({r.x - 1, r.y - 1}),
                    Fixed({r.x + r.width + 1, r.y + r.height + 1}),
                    colour * 0.45,
                    1,
                    cv::LINE_AA,
                    kShift);
      cv::rectangle(image_area,
                    Fixed({r.x, r.y}),
                    Fixed({r.x + r.width, r.y + r.height}),
                    colour,
                    1,
                    cv::LINE_AA,
                    kShift);
    }
    // Used patches: opaque tiles with a dark edge on a layer, in drawing
    // order, so that a patch on top hides the edges of those below (overlaps
    // read as a stack of cards, not a grid of lines); the layer is blended
    // once, so the texture shows through and overlaps do not darken.
    cv::Mat layer = image_area.clone();
    cv::Mat mask(image_area.size(), CV_8U, cv::Scalar(0));
    for (const PatchSample* s : patches) {
      if (!s->used) continue;
      const cv::Rect2d r = square(*s);
      if (std::abs(r.x) > 1e6 || std::abs(r.y) > 1e6) continue;
      const cv::Rect box(static_cast<int>(std::lround(r.x)),
                         static_cast<int>(std::lround(r.y)),
                         static_cast<int>(std::lround(r.width)),
                         static_cast<int>(std::lround(r.height)));
      const cv::Scalar colour = colour_of(*s);
      cv::rectangle(layer, box, colour, cv::FILLED);
      cv::rectangle(layer, box, colour * 0.45, 2);
      cv::rectangle(mask, box, cv::Scalar(255), cv::FILLED);
    }
    cv::Mat blended;
    cv::addWeighted(image_area, 0.3, layer, 0.7, 0, blended);
    blended.copyTo(image_area, mask);

    // Header.
    const std::string name =
        view_name.empty() ? ViewName(result, view_index) : view_name;
    std::string title = "Patches of " + name;
    std::string subtitle;
    if (view_index >= 0 && view_index < static_cast<int>(result.views.size())) {
      const DPViewResult& view = result.views[view_index];
      title += view.used ? ": used" : ": not used";
      if (!view.used && !view.reason.empty()) title += " (" + view.reason + ")";
      if (Finite(view.focus_distance_m) && view.focus_distance_m > 0 &&
          result.success) {
        subtitle = "focus " + Format("%.3g", view.focus_distance_m) + " m; ";
      }
    }
    subtitle += std::to_string(patches.size()) + " selected patches, " +
                std::to_string(num_used) +
                " used; colour = signed blur radius (blue: nearer than the "
                "focus, red: farther)";
    DrawHeader(canvas, result, title, subtitle, kOverlayHeader - 6);
    if (patches.empty()) {
      const cv::Rect box(image_rect.x + image_rect.width / 2 - 220,
                         image_rect.y + image_rect.height / 2 - 30,
                         440,
                         60);
      cv::rectangle(canvas, box, cv::Scalar(245, 245, 245), cv::FILLED);
      cv::rectangle(canvas, box, cv::Scalar(180, 180, 180), 1);
      DrawNoData(canvas, box, "no selected patches in this view");
    }

    // Colour bar: +limit (far, red) at the top.
    const int bar_x = image_rect.x + image_rect.width + 40;
    const int bar_top = kOverlayHeader + 70;
    const int bar_height = 300;
    const int bar_width = 24;
    for (int i = 0; i < bar_height; ++i) {
      const double t = 1 - 2.0 * (i + 0.5) / bar_height;
      cv::line(canvas,
               {bar_x, bar_top + i},
               {bar_x + bar_width - 1, bar_top + i},
               DivergingColour(t),
               1);
    }
    cv::rectangle(
        canvas,
        cv::Rect(bar_x - 1, bar_top - 1, bar_width + 2, bar_height + 2),
        kAxisColour,
        1);
    PutText(canvas,
            "blur radius",
            {bar_x - 25, kOverlayHeader + 16},
            0.45,
            kTextColour);
    PutText(canvas,
            "(DP-frame px)",
            {bar_x - 25, kOverlayHeader + 34},
            0.45,
            kTextColour);
    for (int k = -2; k <= 2; ++k) {
      const double value = limit * k / 2.0;
      const int y =
          bar_top +
          static_cast<int>(std::lround((1 - (k + 2) / 4.0) * bar_height));
      cv::line(canvas,
               {bar_x + bar_width, y},
               {bar_x + bar_width + 5, y},
               kAxisColour,
               1);
      std::string label = FormatValue(value);
      if (value > 0) label = "+" + label;
      PutText(canvas, label, {bar_x + bar_width + 9, y + 5}, 0.45, kTextColour);
    }
    PutText(canvas, "far (+)", {bar_x - 5, bar_top - 17}, 0.45, kMutedText);
    PutText(canvas,
            "near (-)",
            {bar_x - 5, bar_top + bar_height + 27},
            0.45,
            kMutedText);

    // Legend under the image.
    const int legend_y =
        kOverlayHeader + std::max(display_size.height, 420) + 28;
    const cv::Scalar sample = DivergingColour(0.8);
    LegendEntry used_entry{
        "used in the estimate (" + std::to_string(num_used) + ")",
        sample,
        Glyph::kFilledSquare};
    LegendEntry unused_entry{
        "selected, not used (" +
            std::to_string(static_cast<int>(patches.size()) - num_used) + ")",
        sample,
        Glyph::kOutlineSquare};
    DrawGlyph(canvas, used_entry, cv::Point2d(20, legend_y));
    PutText(canvas, used_entry.label, {52, legend_y + 5}, 0.48, kTextColour);
    const int second_x = 70 + TextSize(used_entry.label, 0.48, 1).width + 20;
    DrawGlyph(canvas, unused_entry, cv::Point2d(second_x, legend_y));
    PutText(canvas,
            unused_entry.label,
            {second_x + 32, legend_y + 5},
            0.48,
            kTextColour);
    const std::string note =
        "square = patch (" + Format("%.0f", patch_size_px) +
        " px); colours clipped at +-" + FormatValue(limit) + " px";
    cv::Point note_at(
        second_x + 52 + TextSize(unused_entry.label, 0.48, 1).width + 20,
        legend_y + 5);
    if (note_at.x + TextSize(note, 0.48, 1).width > canvas.cols - 10) {
      note_at = cv::Point(20, legend_y + 29);  // narrow picture: next line
    }
    PutText(canvas, note, note_at, 0.48, kMutedText);
  } catch (...) {
    // Keep what was drawn.
  }
  return canvas;
}

bool WritePatchOverlay(const cv::Mat& image,
                       const std::string& view_name,
                       int view_index,
                       const DPScaleResult& result,
                       double patch_size_px,
                       const std::string& path) {
  try {
    return WritePng(
        RenderPatchOverlay(image, view_name, view_index, result, patch_size_px),
        path);
  } catch (...) {
    return false;
  }
}

// ============================================================== Files ===

std::string PlotFileComponent(const std::string& view_name) {
  std::string name = view_name;
  const size_t slash = name.find_last_of("/\\");
  const size_t dot = name.find_last_of('.');
  const size_t base = slash == std::string::npos ? 0 : slash + 1;
  if (dot != std::string::npos && dot > base) name.erase(dot);
  for (char& c : name) {
    const bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') ||
                    (c >= '0' && c <= '9') || c == '.' || c == '_' || c == '-';
    if (!ok) c = '_';
  }
  if (name.empty()) name = "view";
  return name;
}

std::vector<std::string> WriteReportPlots(
    const DPScaleResult& result,
    const std::vector<std::pair<int, cv::Mat>>& overlay_images,
    const std::string& report_path,
    int working_patch_size) {
  std::vector<std::string> written;
  try {
    std::string stem = report_path;
    const size_t slash = stem.find_last_of('/');
    const size_t dot = stem.find_last_of('.');
    const size_t base = slash == std::string::npos ? 0 : slash + 1;
    if (dot != std::string::npos && dot > base) stem.erase(dot);

    const std::string blur_path = stem + "_blur_fit.png";
    if (WriteBlurFitPlot(result, blur_path)) written.push_back(blur_path);
    const std::string loss_path = stem + "_loss.png";
    if (WriteLossCurvePlot(result, loss_path)) written.push_back(loss_path);

    const std::map<int, double> frame_per_working =
        FramePerWorkingPixel(result);
    std::set<std::string> used_names;
    for (const auto& overlay : overlay_images) {
      try {
        const int view = overlay.first;
        const cv::Mat& image = overlay.second;
        if (image.empty()) continue;
        std::string component = PlotFileComponent(ViewName(result, view));
        if (used_names.count(component)) {
          component += "_" + std::to_string(view);
        }
        used_names.insert(component);
        double patch_size = 0;  // 0 = the overlay's default geometry
        if (working_patch_size > 0) {
          double ratio = kNaN;
          const auto it = frame_per_working.find(view);
          if (it != frame_per_working.end()) ratio = it->second;
          if (!Finite(ratio)) {
            try {
              ratio = 1.0 / DefaultPatchGeometry(image.size()).resize_factor;
            } catch (...) {
              ratio = 1;
            }
          }
          patch_size = working_patch_size * (Finite(ratio) ? ratio : 1.0);
        }
        const std::string path = stem + "_patches_" + component + ".png";
        if (WritePatchOverlay(image,
                              ViewName(result, view),
                              view,
                              result,
                              patch_size,
                              path)) {
          written.push_back(path);
        }
      } catch (...) {
        // One bad image must not cost the others.
      }
    }
  } catch (...) {
    // Report what was written.
  }
  return written;
}

}  // namespace dpsfm
