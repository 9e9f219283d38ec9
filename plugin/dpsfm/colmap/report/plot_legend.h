// Legends of the report pictures: a glyph per entry (what the entry looks
// like in the plot) and its label, in a box or laid out by the caller.
#pragma once

#include <string>
#include <vector>

#include <opencv2/core.hpp>

namespace dpsfm {
namespace plot {

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

// The entry's glyph, 26 px wide, starting at `left_middle`.
void DrawGlyph(cv::Mat& canvas,
               const LegendEntry& entry,
               const cv::Point2d& left_middle);

// A boxed vertical legend with its top-left corner at `origin`.
cv::Rect LegendBox(const std::vector<LegendEntry>& entries,
                   const cv::Point& origin);

// Draws the legend in `box` (from LegendBox, maybe moved).
void DrawLegend(cv::Mat& canvas,
                const std::vector<LegendEntry>& entries,
                const cv::Rect& box);

}  // namespace plot
}  // namespace dpsfm
