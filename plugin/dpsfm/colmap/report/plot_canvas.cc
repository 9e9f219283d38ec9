#include "dpsfm/colmap/report/plot_canvas.h"

#include <algorithm>
#include <cmath>
#include <exception>
#include <vector>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

namespace dpsfm {
namespace plot {
namespace {

constexpr double kShiftScale = 1 << kShift;

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

}  // namespace

bool Finite(double v) { return std::isfinite(v); }

double Clamp(double v, double lo, double hi) {
  return std::min(std::max(v, lo), hi);
}

cv::Point Fixed(const cv::Point2d& p) {
  return cv::Point(static_cast<int>(std::lround(p.x * kShiftScale)),
                   static_cast<int>(std::lround(p.y * kShiftScale)));
}

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
                 bool dashed) {
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
             int thickness) {
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

cv::Scalar DivergingColour(double t) {
  if (!Finite(t)) return cv::Scalar(150, 150, 150);
  const double u = (Clamp(t, -1, 1) + 1) / 2 * (kNumDiverging - 1);
  const int i = std::min(static_cast<int>(u), kNumDiverging - 2);
  const double f = u - i;
  return kDiverging[i] * (1 - f) + kDiverging[i + 1] * f;
}

double NiceCeil(double v) {
  if (!(v > 0) || !Finite(v)) return 1;
  const double magnitude = std::pow(10.0, std::floor(std::log10(v)));
  for (const double m : {1.0, 1.5, 2.0, 2.5, 3.0, 4.0, 5.0, 6.0, 8.0, 10.0}) {
    if (m * magnitude >= v * (1 - 1e-9)) return m * magnitude;
  }
  return 10 * magnitude;
}

bool WritePng(const cv::Mat& image,
              const std::string& path,
              std::string* error) {
  std::string reason;
  if (image.empty()) {
    reason = "empty picture";
  } else if (path.empty()) {
    reason = "empty path";
  } else {
    try {
      if (cv::imwrite(path, image)) return true;
      reason = "cannot write " + path;
    } catch (const std::exception& e) {
      // OpenCV throws cv::Exception for what its encoder rejects.
      reason = e.what();
    }
  }
  if (error != nullptr) *error = reason;
  return false;
}

bool RenderPng(const std::function<cv::Mat()>& render,
               const std::string& path,
               std::string* error) {
  cv::Mat image;
  try {
    image = render();
  } catch (const std::exception& e) {
    if (error != nullptr) *error = e.what();
    return false;
  } catch (...) {
    // Counted as a failure like any other: the caller reports it.
    if (error != nullptr) *error = "unknown exception";
    return false;
  }
  return WritePng(image, path, error);
}

}  // namespace plot
}  // namespace dpsfm
