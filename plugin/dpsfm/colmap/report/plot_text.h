// Text in the report pictures: number formats for labels, and OpenCV's
// Hershey text made safe for arbitrary strings (ASCII only), aligned,
// shortened, word-wrapped, rotated, and the title block at the top of a
// picture.
#pragma once

#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "dpsfm/colmap/report/plot_canvas.h"

namespace dpsfm {
namespace plot {

// Hershey fonts are ASCII only: anything else (UTF-8 in view names) would be
// drawn as garbage, so it becomes '?'; line breaks and tabs become spaces.
std::string Printable(const std::string& text);

// snprintf of one number.
std::string Format(const char* format, double value);

// Compact number for labels: 4 significant digits, no exponent for the
// magnitudes scales usually have; "n/a" for NaN and infinities.
std::string FormatValue(double value);

// Size of `text` in the plot font at `scale`.
cv::Size TextSize(const std::string& text, double scale, int thickness);

enum class Align { kLeft, kCenter, kRight };

// `anchor` is the baseline point at the left edge, centre or right edge.
void PutText(cv::Mat& canvas,
             const std::string& text,
             cv::Point anchor,
             double scale,
             const cv::Scalar& colour,
             int thickness = 1,
             Align align = Align::kLeft);

// Shortens `text` to fit `max_width` px by replacing its middle with "...".
std::string Ellipsize(const std::string& text,
                      double scale,
                      int thickness,
                      int max_width);

// Greedy word wrap to `max_width` px; at most `max_lines` lines (the last one
// ellipsized where there are more; a word wider than the width too).
std::vector<std::string> WrapText(const std::string& text,
                                  double scale,
                                  int thickness,
                                  int max_width,
                                  int max_lines);

// Draws wrapped text from baseline y; returns the baseline after the last
// line. `line_height` <= 0: 1.7 times the font's height.
int PutWrapped(cv::Mat& canvas,
               const std::string& text,
               int x,
               int y,
               int max_width,
               int max_lines,
               double scale,
               const cv::Scalar& colour,
               int thickness = 1,
               int line_height = 0);

// Text rotated by 90 degrees (reading upwards) centred on `centre`: OpenCV
// cannot rotate text, so it is drawn flat and the patch rotated.
void PutVerticalText(cv::Mat& canvas,
                     const std::string& text,
                     cv::Point centre,
                     double scale,
                     const cv::Scalar& colour,
                     int thickness = 1);

// A picture's header: a non-empty `alert` (a failed estimate's reason)
// first, in red, because that is what a reader must see first; then the
// title (bold) and an optional subtitle. Every word is drawn, on as many
// lines as it takes.
//
// The rows the header of a picture `width` px wide takes, at least
// min_rows.
int HeaderRows(int width,
               int min_rows,
               const std::string& alert,
               const std::string& title,
               const std::string& subtitle);

// The header on a strip of `like`'s width and type, HeaderRows tall.
cv::Mat HeaderStrip(const cv::Mat& like,
                    int min_rows,
                    const std::string& alert,
                    const std::string& title,
                    const std::string& subtitle);

// `body` from row `body_top` down under its header (HeaderStrip): the
// picture grows when the header needs more than body_top rows.
cv::Mat WithHeader(const cv::Mat& body,
                   int body_top,
                   const std::string& alert,
                   const std::string& title,
                   const std::string& subtitle);

// `body` down to row `body_bottom` over `text` wrapped (every word, as
// many lines of `line_height` as it takes): the picture grows when the text
// needs more than the rows below body_bottom.
cv::Mat WithFooter(const cv::Mat& body,
                   int body_bottom,
                   const std::string& text,
                   double scale,
                   int line_height);

}  // namespace plot
}  // namespace dpsfm
