#include "dpsfm/colmap/report/patch_overlay_plot.h"

#include <algorithm>
#include <cmath>
#include <optional>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "dpsfm/colmap/report/plot_axes.h"
#include "dpsfm/colmap/report/plot_canvas.h"
#include "dpsfm/colmap/report/plot_legend.h"
#include "dpsfm/colmap/report/plot_result.h"
#include "dpsfm/colmap/report/plot_text.h"
#include "dpsfm/core/util/statistics.h"

namespace dpsfm {
namespace {

using plot::DivergingColour;
using plot::Finite;
using plot::Fixed;
using plot::FormatValue;
using plot::kAxisColour;
using plot::kMutedText;
using plot::kShift;
using plot::kTextColour;
using plot::PutText;

constexpr int kOverlayMarginX = 10;
constexpr int kOverlayHeader = 96;
constexpr int kOverlayRightPanel = 190;
constexpr int kOverlayFooter = 66;
constexpr int kOverlayMaxWidth = 1600;
constexpr int kOverlayMinWidth = 640;
// The image area is at least this tall, so that the colour bar fits.
constexpr int kOverlayMinImageHeight = 420;

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

// Whether DisplayImage can show `image`: cv::cvtColor turns colour images of
// these depths only into grey.
bool GreyConvertible(const cv::Mat& image) {
  if (image.channels() != 3 && image.channels() != 4) return true;
  const int depth = image.depth();
  return depth == CV_8U || depth == CV_16U || depth == CV_32F;
}

// Grey display image: the DP frame is linear and often dark, so it is
// normalised to its 99.5th percentile and gamma-encoded; the contrast is then
// compressed a little so that both white and black squares stand out.
// `image` must be GreyConvertible.
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

// Where things go in the picture of an image.
struct OverlayLayout {
  cv::Size image_size;  // of the DP frame
  double d = 1;         // picture pixels per DP-frame pixel
  cv::Rect image_rect;  // the displayed image in the picture
  cv::Size canvas_size;
  int legend_y = 0;  // the legend's middle line, under the image
};

OverlayLayout LayoutFor(const cv::Size& image_size) {
  OverlayLayout layout;
  layout.image_size = image_size;
  layout.d = OverlayScale(image_size);
  const cv::Size display_size(
      std::max(1, static_cast<int>(std::lround(image_size.width * layout.d))),
      std::max(1, static_cast<int>(std::lround(image_size.height * layout.d))));
  layout.image_rect = cv::Rect(
      kOverlayMarginX, kOverlayHeader, display_size.width, display_size.height);
  const int image_height =
      std::max(display_size.height, kOverlayMinImageHeight);
  layout.canvas_size =
      cv::Size(kOverlayMarginX + display_size.width + kOverlayRightPanel,
               kOverlayHeader + image_height + kOverlayFooter);
  layout.legend_y = kOverlayHeader + image_height + 28;
  return layout;
}

// The patch side in DP-frame pixels: `patch_size_px` if it is one, else
// that of the frame's DefaultPatchGeometry, else 3 % of the frame.
double PatchSide(double patch_size_px, const cv::Size& image_size) {
  if (patch_size_px > 0 && Finite(patch_size_px)) return patch_size_px;
  patch_size_px = 0;
  const std::optional<PatchGeometry> geometry =
      plot::DefaultFrameGeometry(image_size);
  if (geometry) patch_size_px = geometry->patch_size / geometry->resize_factor;
  if (!(patch_size_px > 0) || !Finite(patch_size_px)) {
    patch_size_px = 0.03 * std::max(image_size.width, image_size.height);
  }
  return patch_size_px;
}

// The view's selected patches with a position, in drawing order, and the
// colour scale's limit.
struct OverlayPatches {
  std::vector<const PatchSample*> patches;
  int num_used = 0;
  double limit = 1;  // |blur| (DP-frame px) at the colour map's ends
};

OverlayPatches SelectPatches(const DPScaleResult& result, int view_index) {
  OverlayPatches selection;
  std::vector<double> magnitudes;
  for (const PatchSample& s : result.patches) {
    if (s.view != view_index || !s.selected) continue;
    if (!Finite(s.x) || !Finite(s.y)) continue;
    selection.patches.push_back(&s);
    magnitudes.push_back(std::abs(s.radius_frame_px));
    if (s.used) ++selection.num_used;
  }
  // Colour limit: a round number just above the 98th percentile of |r|, so
  // one wild patch does not wash out the rest.
  selection.limit =
      plot::NiceCeil(std::max(NearestRankQuantile(magnitudes, 0.98), 0.1));
  // Unused patches first (underneath), then used ones by confidence so the
  // most trusted are on top.
  std::stable_sort(selection.patches.begin(),
                   selection.patches.end(),
                   [](const PatchSample* a, const PatchSample* b) {
                     if (a->used != b->used) return !a->used;
                     return a->confidence < b->confidence;
                   });
  return selection;
}

// The grey image in its frame; a grey area for an image it cannot show.
void DrawImage(cv::Mat& canvas,
               const cv::Mat& image,
               const OverlayLayout& layout) {
  if (GreyConvertible(image)) {
    DisplayImage(image, layout.image_rect.size())
        .copyTo(canvas(layout.image_rect));
  } else {
    canvas(layout.image_rect).setTo(cv::Scalar(128, 128, 128));
  }
  cv::rectangle(canvas, layout.image_rect, kAxisColour, 1);
}

// Patch squares in the coordinates of the image area.
class PatchSquares {
 public:
  PatchSquares(const OverlayLayout& layout, double patch_side)
      : image_size_(layout.image_size),
        origin_(layout.image_rect.x, layout.image_rect.y),
        half_(std::max(2.0, 0.5 * patch_side * layout.d)) {}

  cv::Rect2d Of(const PatchSample& s) const {
    const cv::Point2d c = PatchOverlayPoint(image_size_, s.x, s.y) - origin_;
    return cv::Rect2d(c.x - half_, c.y - half_, 2 * half_, 2 * half_);
  }

 private:
  cv::Size image_size_;
  cv::Point2d origin_;
  double half_;
};

// Far-away squares (a patch at 1e300) are skipped: fixed point would
// overflow.
bool Drawable(const cv::Rect2d& r) {
  return !(std::abs(r.x) > 1e6 || std::abs(r.y) > 1e6);
}

// Selected-but-unused patches: thin outlines (a dark rim outside the colour
// keeps near-white ones visible), under the used ones.
void DrawUnusedPatches(cv::Mat& image_area,
                       const OverlayPatches& selection,
                       const PatchSquares& squares) {
  for (const PatchSample* s : selection.patches) {
    if (s->used) continue;
    const cv::Rect2d r = squares.Of(*s);
    if (!Drawable(r)) continue;
    const cv::Scalar colour =
        DivergingColour(s->radius_frame_px / selection.limit);
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
}

// Used patches: opaque tiles with a dark edge on a layer, in drawing order,
// so that a patch on top hides the edges of those below (overlaps read as a
// stack of cards, not a grid of lines); the layer is blended once, so the
// texture shows through and overlaps do not darken.
void DrawUsedPatches(cv::Mat& image_area,
                     const OverlayPatches& selection,
                     const PatchSquares& squares) {
  cv::Mat layer = image_area.clone();
  cv::Mat mask(image_area.size(), CV_8U, cv::Scalar(0));
  for (const PatchSample* s : selection.patches) {
    if (!s->used) continue;
    const cv::Rect2d r = squares.Of(*s);
    if (!Drawable(r)) continue;
    const cv::Rect box(static_cast<int>(std::lround(r.x)),
                       static_cast<int>(std::lround(r.y)),
                       static_cast<int>(std::lround(r.width)),
                       static_cast<int>(std::lround(r.height)));
    const cv::Scalar colour =
        DivergingColour(s->radius_frame_px / selection.limit);
    cv::rectangle(layer, box, colour, cv::FILLED);
    cv::rectangle(layer, box, colour * 0.45, 2);
    cv::rectangle(mask, box, cv::Scalar(255), cv::FILLED);
  }
  cv::Mat blended;
  cv::addWeighted(image_area, 0.3, layer, 0.7, 0, blended);
  blended.copyTo(image_area, mask);
}

// The title (the view, whether it was used and why not) and subtitle
// (focus, counts, what the colours mean).
std::pair<std::string, std::string> OverlayHeading(
    const DPScaleResult& result,
    const std::string& view_name,
    int view_index,
    const OverlayPatches& selection) {
  const std::string name =
      view_name.empty() ? plot::ViewName(result, view_index) : view_name;
  std::string title = "Patches of " + name;
  std::string subtitle;
  if (view_index >= 0 && view_index < static_cast<int>(result.views.size())) {
    const DPViewResult& view = result.views[view_index];
    title += view.used ? ": used" : ": not used";
    if (!view.used && !view.reason.empty()) title += " (" + view.reason + ")";
    if (Finite(view.focus_distance_m) && view.focus_distance_m > 0 &&
        result.success) {
      subtitle =
          "focus " + plot::Format("%.3g", view.focus_distance_m) + " m; ";
    }
  }
  subtitle += std::to_string(selection.patches.size()) + " selected patches, " +
              std::to_string(selection.num_used) +
              " used; colour = signed blur radius (blue: nearer than the "
              "focus, red: farther)";
  return {title, subtitle};
}

// A note on an image without patches.
void DrawNoPatches(cv::Mat& canvas,
                   const OverlayPatches& selection,
                   const cv::Rect& image_rect) {
  if (!selection.patches.empty()) return;
  const cv::Rect box(image_rect.x + image_rect.width / 2 - 220,
                     image_rect.y + image_rect.height / 2 - 30,
                     440,
                     60);
  cv::rectangle(canvas, box, cv::Scalar(245, 245, 245), cv::FILLED);
  cv::rectangle(canvas, box, cv::Scalar(180, 180, 180), 1);
  plot::DrawNoData(canvas, box, "no selected patches in this view");
}

// Colour bar right of the image, +limit (far, red) at the top.
void DrawColourBar(cv::Mat& canvas, const cv::Rect& image_rect, double limit) {
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
  cv::rectangle(canvas,
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
    const int y = bar_top + static_cast<int>(
                                std::lround((1 - (k + 2) / 4.0) * bar_height));
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
}

// Legend under the image: the two kinds of square and the scale's note.
void DrawOverlayLegend(cv::Mat& canvas,
                       int legend_y,
                       const OverlayPatches& selection,
                       double patch_side) {
  const cv::Scalar sample = DivergingColour(0.8);
  const int num_selected = static_cast<int>(selection.patches.size());
  const plot::LegendEntry used_entry{
      "used in the estimate (" + std::to_string(selection.num_used) + ")",
      sample,
      plot::Glyph::kFilledSquare};
  const plot::LegendEntry unused_entry{
      "selected, not used (" +
          std::to_string(num_selected - selection.num_used) + ")",
      sample,
      plot::Glyph::kOutlineSquare};
  plot::DrawGlyph(canvas, used_entry, cv::Point2d(20, legend_y));
  PutText(canvas, used_entry.label, {52, legend_y + 5}, 0.48, kTextColour);
  const int second_x =
      70 + plot::TextSize(used_entry.label, 0.48, 1).width + 20;
  plot::DrawGlyph(canvas, unused_entry, cv::Point2d(second_x, legend_y));
  PutText(canvas,
          unused_entry.label,
          {second_x + 32, legend_y + 5},
          0.48,
          kTextColour);
  const std::string note =
      "square = patch (" + plot::Format("%.0f", patch_side) +
      " px); colours clipped at +-" + FormatValue(selection.limit) + " px";
  cv::Point note_at(
      second_x + 52 + plot::TextSize(unused_entry.label, 0.48, 1).width + 20,
      legend_y + 5);
  if (note_at.x + plot::TextSize(note, 0.48, 1).width > canvas.cols - 10) {
    note_at = cv::Point(20, legend_y + 29);  // narrow picture: next line
  }
  PutText(canvas, note, note_at, 0.48, kMutedText);
}

}  // namespace

cv::Point2d PatchOverlayPoint(const cv::Size& frame_size, double x, double y) {
  const double d = OverlayScale(frame_size);
  return {kOverlayMarginX + (x + 0.5) * d - 0.5,
          kOverlayHeader + (y + 0.5) * d - 0.5};
}

cv::Mat RenderPatchOverlay(const cv::Mat& image,
                           const std::string& view_name,
                           int view_index,
                           const DPScaleResult& result,
                           double patch_size_px,
                           const cv::Size& frame_size) {
  if (image.empty() || image.cols <= 0 || image.rows <= 0) return cv::Mat();
  const cv::Size frame = frame_size.empty() ? image.size() : frame_size;
  const OverlayLayout layout = LayoutFor(frame);
  cv::Mat canvas(layout.canvas_size, CV_8UC3, plot::kWhite);
  DrawImage(canvas, image, layout);
  const double patch_side = PatchSide(patch_size_px, frame);
  const OverlayPatches selection = SelectPatches(result, view_index);
  const PatchSquares squares(layout, patch_side);
  cv::Mat image_area = canvas(layout.image_rect);
  DrawUnusedPatches(image_area, selection, squares);
  DrawUsedPatches(image_area, selection, squares);
  DrawNoPatches(canvas, selection, layout.image_rect);
  DrawColourBar(canvas, layout.image_rect, selection.limit);
  DrawOverlayLegend(canvas, layout.legend_y, selection, patch_side);
  const auto heading = OverlayHeading(result, view_name, view_index, selection);
  return plot::WithHeader(canvas,
                          kOverlayHeader - 6,
                          plot::FailureAlert(result),
                          heading.first,
                          heading.second);
}

bool WritePatchOverlay(const cv::Mat& image,
                       const std::string& view_name,
                       int view_index,
                       const DPScaleResult& result,
                       double patch_size_px,
                       const std::string& path,
                       std::string* error) {
  return plot::RenderPng(
      [&] {
        return RenderPatchOverlay(
            image, view_name, view_index, result, patch_size_px);
      },
      path,
      error);
}

}  // namespace dpsfm
