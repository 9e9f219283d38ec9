// The drawing layer of the report pictures: the colours they share,
// anti-aliased segments, dots and diamonds that tolerate NaN and far-away
// points, the diverging colour map of signed blur, and PNG writing. Drawn
// with OpenCV only (no plotting dependency).
#pragma once

#include <functional>
#include <limits>
#include <string>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

namespace dpsfm {
namespace plot {

inline constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
inline constexpr double kInf = std::numeric_limits<double>::infinity();

inline const cv::Scalar kWhite(255, 255, 255);
inline const cv::Scalar kTextColour(30, 30, 30);
inline const cv::Scalar kMutedText(90, 90, 90);
inline const cv::Scalar kFailureColour(30, 30, 190);
inline const cv::Scalar kAxisColour(70, 70, 70);
inline const cv::Scalar kGridColour(232, 232, 232);

// Sub-pixel precision of drawn geometry (cv::line & co. take fixed point).
inline constexpr int kShift = 4;

bool Finite(double v);
double Clamp(double v, double lo, double hi);

// `p` in the fixed point of kShift.
cv::Point Fixed(const cv::Point2d& p);

// Liang-Barsky clipping of segment a-b to `box`; false if nothing is left.
// Needed before the fixed-point conversion: a line to a far-away point would
// overflow int.
bool ClipSegment(const cv::Rect2d& box, cv::Point2d* a, cv::Point2d* b);

// A segment clipped to the image (nothing for a non-finite end); dashed:
// 9 px dashes with 6 px gaps.
void DrawSegment(cv::Mat& image,
                 cv::Point2d a,
                 cv::Point2d b,
                 const cv::Scalar& colour,
                 int thickness,
                 bool dashed = false);

// A disc (or a ring of `thickness`); nothing for a centre that is not finite
// or lies more than 50 px outside the image.
void DrawDot(cv::Mat& image,
             const cv::Point2d& centre,
             double radius,
             const cv::Scalar& colour,
             int thickness = cv::FILLED);

// A filled diamond of half-diagonal `r` with an edge.
void DrawDiamond(cv::Mat& image,
                 const cv::Point2d& c,
                 double r,
                 const cv::Scalar& fill,
                 const cv::Scalar& edge);

// ColorBrewer's RdBu: t in [-1, 1], -1 = deep blue, 0 = near white, +1 =
// deep red; grey for NaN.
cv::Scalar DivergingColour(double t);

// A round number at or above v for the colour bar limit, in steps fine
// enough (1, 1.5, 2, ... x 10^k) that the colours stay saturated.
double NiceCeil(double v);

// Writes `image` as PNG (the format follows the path's extension). False
// for an empty image or path, an image or extension OpenCV rejects (its
// exception's what() is the reason) or a file that cannot be written, with
// the reason in *error (if given).
bool WritePng(const cv::Mat& image,
              const std::string& path,
              std::string* error = nullptr);

// Renders with `render` and writes the picture with WritePng. An exception
// of `render` is caught and makes it return false with its what() (or
// "unknown exception") in *error: a missing picture must never fail a run.
bool RenderPng(const std::function<cv::Mat()>& render,
               const std::string& path,
               std::string* error = nullptr);

}  // namespace plot
}  // namespace dpsfm
