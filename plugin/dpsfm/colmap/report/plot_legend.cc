#include "dpsfm/colmap/report/plot_legend.h"

#include <algorithm>

#include <opencv2/imgproc.hpp>

#include "dpsfm/colmap/report/plot_canvas.h"
#include "dpsfm/colmap/report/plot_text.h"

namespace dpsfm {
namespace plot {

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

}  // namespace plot
}  // namespace dpsfm
