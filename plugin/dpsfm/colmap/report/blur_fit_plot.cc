#include "dpsfm/colmap/report/blur_fit_plot.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <optional>
#include <sstream>
#include <utility>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "dpsfm/colmap/report/plot_canvas.h"
#include "dpsfm/colmap/report/plot_legend.h"
#include "dpsfm/colmap/report/plot_result.h"
#include "dpsfm/colmap/report/plot_text.h"
#include "dpsfm/core/optics/lens_model.h"

namespace dpsfm {
namespace {

using plot::Axes;
using plot::DrawDot;
using plot::DrawSegment;
using plot::Finite;
using plot::Glyph;
using plot::kAxisColour;
using plot::kMutedText;
using plot::kNaN;
using plot::kTextColour;
using plot::LegendEntry;
using plot::PutText;
using plot::Range;

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

// Where the panels start; the header above them grows the picture when it
// needs more room (plot::WithHeader).
constexpr int kPanelTop = 108;
constexpr int kHeaderRows = kPanelTop - 28;
constexpr int kWidth = 1000;  // the picture's

// One patch as the picture shows it (radii in DP-frame pixels).
struct BlurPoint {
  int view;
  double inv_depth, measured, predicted;
};

// A view's model line in the left panel, from (x0, y0) to (x1, y1).
struct ModelLine {
  double x0, x1, y0, y1;
};

// Everything the picture shows, worked out before anything is drawn.
struct BlurFitData {
  // Whether used patches of used views are shown (else the selected ones).
  bool any_used = false;
  std::map<int, std::vector<BlurPoint>> by_view;
  // (-number of points, view): views with the most points first.
  std::vector<std::pair<int, int>> order;
  std::map<int, cv::Scalar> colour;
  int num_points = 0, num_other_views = 0, num_other_points = 0;
  bool have_left = false, have_right = false;
  std::map<int, ModelLine> lines;
  // Points outside a panel's ranges.
  int off_scale = 0;
  Axes left, right;
  // The scale the model is drawn under (ModelScale), and whether it is the
  // answer's.
  double model_scale = kNaN;
  bool model_is_answer = false;
  // Median |measured - predicted| of the points drawn (DP-frame px).
  double median_residual = kNaN;
};

// The scale the model is drawn under: the answer's, else the DP data's own
// reading s* (a refused run's, not adopted); NaN without either.
double ModelScale(const DPScaleResult& result, bool* is_answer) {
  *is_answer = result.success && Finite(result.scale) && result.scale > 0;
  if (*is_answer) return result.scale;
  if (Finite(result.scale_initial) && result.scale_initial > 0) {
    return result.scale_initial;
  }
  return kNaN;
}

// A patch's radius predicted under `scale` from the report's lens and
// fitted focus distance of its view (DP-frame px); NaN without them.
double PredictedUnder(const DPScaleResult& result,
                      const PatchSample& s,
                      double scale) {
  if (!Finite(scale) || s.view < 0 ||
      s.view >= static_cast<int>(result.views.size()) || !(s.depth > 0)) {
    return kNaN;
  }
  const DPViewResult& view = result.views[s.view];
  if (!view.lens.Check() || !Finite(view.focus_distance_model)) return kNaN;
  return PredictBlurRadiusPx(view.lens,
                             view.lens.PixelPitchMm(),
                             scale,
                             view.focus_distance_model,
                             s.depth);
}

// What to show: used patches of used views; if there are none (a failed
// estimate), the selected ones, so that the reader sees why it failed.
void CollectPoints(const DPScaleResult& result, BlurFitData* data) {
  const std::map<int, double> frame_per_working =
      plot::FramePerWorkingPixel(result);
  for (const PatchSample& s : result.patches) {
    if (s.used && plot::ViewUsed(result, s.view)) data->any_used = true;
  }
  for (const PatchSample& s : result.patches) {
    const bool shown = data->any_used
                           ? (s.used && plot::ViewUsed(result, s.view))
                           : s.selected;
    if (!shown) continue;
    BlurPoint p;
    p.view = s.view;
    p.inv_depth = s.depth > 0 && Finite(s.depth) ? 1.0 / s.depth : kNaN;
    p.measured = s.radius_frame_px;
    // The core's prediction under the answer; a refused run's under s*.
    const auto ratio = frame_per_working.find(s.view);
    p.predicted = data->model_is_answer && ratio != frame_per_working.end()
                      ? s.predicted_radius_px * ratio->second
                      : PredictedUnder(result, s, data->model_scale);
    if (!Finite(p.measured)) continue;
    data->by_view[s.view].push_back(p);
  }
}

// Colours: the views with the most points get the palette, the rest are
// grey (drawn underneath) so that more than 10 views stay readable.
void AssignColours(BlurFitData* data) {
  for (const auto& v : data->by_view) {
    data->order.emplace_back(-static_cast<int>(v.second.size()), v.first);
  }
  std::sort(data->order.begin(), data->order.end());
  for (size_t i = 0; i < data->order.size(); ++i) {
    const int view = data->order[i].second;
    data->num_points += -data->order[i].first;
    if (static_cast<int>(i) < kNumPaletteColours) {
      data->colour[view] = kPalette[i];
    } else {
      data->colour[view] = kOtherViewsColour;
      ++data->num_other_views;
      data->num_other_points += -data->order[i].first;
    }
  }
}

// Axis ranges that a few wild values cannot squash (see RobustRange), not
// padded yet: the model lines are fitted within them first.
void SetDataRanges(BlurFitData* data) {
  std::vector<double> inv_depths, measured_left, both_right;
  std::vector<double> residuals;
  for (const auto& v : data->by_view) {
    for (const BlurPoint& p : v.second) {
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
  data->have_left = !inv_depths.empty();
  data->have_right = !residuals.empty();
  if (data->have_right) {
    std::nth_element(residuals.begin(),
                     residuals.begin() + residuals.size() / 2,
                     residuals.end());
    data->median_residual = residuals[residuals.size() / 2];
  }
  data->left.x = plot::RobustRange(inv_depths);
  data->left.y = plot::RobustRange(measured_left);
  data->right.x = plot::RobustRange(both_right);
}

// The lens formula's line r(1/z') under `scale`, from r at
// 1/z' = 1 and 2; false without a usable lens, focus distance or scale.
bool LensModelLine(const DPScaleResult& result,
                   int view_index,
                   double scale,
                   double* slope,
                   double* intercept) {
  if (view_index < 0 || view_index >= static_cast<int>(result.views.size())) {
    return false;
  }
  const DPViewResult& view = result.views[view_index];
  if (!view.lens.Check() || !Finite(view.focus_distance_model) ||
      !(scale > 0) || !Finite(scale)) {
    return false;
  }
  const double r1 = PredictBlurRadiusPx(view.lens,
                                        view.lens.PixelPitchMm(),
                                        scale,
                                        view.focus_distance_model,
                                        1.0);
  const double r2 = PredictBlurRadiusPx(view.lens,
                                        view.lens.PixelPitchMm(),
                                        scale,
                                        view.focus_distance_model,
                                        0.5);
  *slope = r2 - r1;
  *intercept = r1 - *slope;
  return true;
}

// A view's prediction line over its points' 1/z' within `left_x`: the
// thin-lens radius is affine in 1/z', so a least-squares line through the
// points' predictions reproduces them exactly; without predictions, the
// lens formula under the model's scale.
std::optional<ModelLine> FitModelLine(const DPScaleResult& result,
                                      double data_scale,
                                      int view,
                                      const std::vector<BlurPoint>& points,
                                      const Range& left_x) {
  Range xr;
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  int n = 0;
  for (const BlurPoint& p : points) {
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
  if (!xr.Valid()) return std::nullopt;
  const double det = n * sxx - sx * sx;
  double slope = kNaN, intercept = kNaN;
  if (n >= 2 && det > 1e-12 * std::max(1.0, n * sxx)) {
    slope = (n * sxy - sx * sy) / det;
    intercept = (sy - slope * sx) / n;
  } else {
    LensModelLine(result, view, data_scale, &slope, &intercept);
  }
  if (!Finite(slope) || !Finite(intercept)) return std::nullopt;
  const double pad = 0.03 * std::max(xr.hi - xr.lo, 1e-12);
  ModelLine line;
  line.x0 = xr.lo - pad;
  line.x1 = xr.hi + pad;
  line.y0 = intercept + slope * line.x0;
  line.y1 = intercept + slope * line.x1;
  return line;
}

// Model lines of the views; the left panel's radius range takes them in.
void AddModelLines(const DPScaleResult& result, BlurFitData* data) {
  for (const auto& v : data->by_view) {
    const std::optional<ModelLine> line = FitModelLine(
        result, data->model_scale, v.first, v.second, data->left.x);
    if (!line) continue;
    data->lines[v.first] = *line;
    data->left.y.Add(line->y0);
    data->left.y.Add(line->y1);
  }
}

int CountOffScale(const BlurFitData& data) {
  const Range& lx = data.left.x;
  const Range& ly = data.left.y;
  const Range& r = data.right.x;
  int off_scale = 0;
  for (const auto& v : data.by_view) {
    for (const BlurPoint& p : v.second) {
      const bool left_out =
          Finite(p.inv_depth) && (p.inv_depth < lx.lo || p.inv_depth > lx.hi ||
                                  p.measured < ly.lo || p.measured > ly.hi);
      const bool right_out =
          Finite(p.predicted) && (p.predicted < r.lo || p.predicted > r.hi ||
                                  p.measured < r.lo || p.measured > r.hi);
      if (left_out || right_out) ++off_scale;
    }
  }
  return off_scale;
}

// The points, colours, lines and panels of the picture of `result`. The
// panels sit below the header, which takes more room for a failure.
BlurFitData PrepareBlurFit(const DPScaleResult& result) {
  BlurFitData data;
  data.model_scale = ModelScale(result, &data.model_is_answer);
  CollectPoints(result, &data);
  AssignColours(&data);
  SetDataRanges(&data);
  AddModelLines(result, &data);
  plot::PadRange(&data.left.x, 0.05);
  plot::PadRange(&data.left.y, 0.08);
  plot::PadRange(&data.right.x, 0.06);
  data.right.y = data.right.x;
  data.off_scale = CountOffScale(data);
  const int top = kPanelTop;
  const int height = 520 - top;
  data.left.area = cv::Rect(95, top, 385, height);
  data.right.area = cv::Rect(590, top, 385, height);
  return data;
}

// The title names the scale the model lines and predictions are drawn
// under and the median |measured - predicted| of the points drawn, both
// from the report's own values (DP-frame px).
std::string TitleOf(const BlurFitData& data) {
  std::string title = "Blur vs thin-lens model";
  if (!Finite(data.model_scale)) return title;
  title += data.model_is_answer
               ? " (final s = " + plot::ScaleText(data.model_scale) + ")"
               : " (the DP data's s* = " + plot::ScaleText(data.model_scale) +
                     ", not adopted)";
  if (Finite(data.median_residual)) {
    title += ": median |residual| " +
             plot::Format("%.3g", data.median_residual) + " px";
  }
  return title;
}

std::string BlurFitSubtitle(const BlurFitData& data) {
  const size_t num_views = data.by_view.size();
  std::ostringstream subtitle;
  subtitle << data.num_points << (data.any_used ? " used" : " selected")
           << " patches in " << num_views << " view"
           << (num_views == 1 ? "" : "s");
  if (!data.any_used) subtitle << " (no patch was used)";
  if (data.off_scale > 0) {
    subtitle << ", " << data.off_scale << " off the axes";
  }
  subtitle << "; radii signed (+ = farther than the focus), DP-frame px";
  if (Finite(data.median_residual)) {
    subtitle << "; residual = measured - predicted";
  }
  if (Finite(data.model_scale) && !data.model_is_answer) {
    subtitle << "; the model under the scale the DP data read, which the "
                "run did not adopt (the reason above)";
  }
  return subtitle.str();
}

// Panel titles, grids, ticks and axis labels.
void DrawPanelAxes(cv::Mat& canvas, const BlurFitData& data) {
  const int top = data.left.area.y;
  PutText(canvas,
          "blur against inverse depth; lines: model",
          {data.left.area.x, top - 10},
          0.5,
          kTextColour,
          1);
  PutText(canvas,
          "blur against the model's prediction",
          {data.right.area.x, top - 10},
          0.5,
          kTextColour,
          1);
  plot::DrawAxes(canvas,
                 data.left,
                 "inverse depth 1/z' (1 / model unit)",
                 "measured blur radius (px)");
  plot::DrawAxes(canvas,
                 data.right,
                 "predicted blur radius (px)",
                 "measured blur radius (px)");
}

// The focal plane (r = 0) in the left panel, y = x in the right one.
void DrawReferenceLines(cv::Mat& canvas, const BlurFitData& data) {
  const Axes& left = data.left;
  const Axes& right = data.right;
  if (left.y.lo < 0 && left.y.hi > 0) {
    cv::Mat roi = left.Roi(canvas);
    DrawSegment(roi,
                left.ToLocal(left.x.lo, 0),
                left.ToLocal(left.x.hi, 0),
                cv::Scalar(160, 160, 160),
                1,
                true);
  }
  if (data.have_right) {
    cv::Mat roi = right.Roi(canvas);
    DrawSegment(roi,
                right.ToLocal(right.x.lo, right.x.lo),
                right.ToLocal(right.x.hi, right.x.hi),
                cv::Scalar(0, 0, 0),
                1);
  }
}

// Model lines under the points: the points are the evidence.
void DrawModelLines(cv::Mat& canvas, const BlurFitData& data) {
  cv::Mat roi = data.left.Roi(canvas);
  for (auto it = data.order.rbegin(); it != data.order.rend(); ++it) {
    const auto line = data.lines.find(it->second);
    if (line == data.lines.end()) continue;
    DrawSegment(roi,
                data.left.ToLocal(line->second.x0, line->second.y0),
                data.left.ToLocal(line->second.x1, line->second.y1),
                data.colour.at(it->second),
                2);
  }
}

// Grey views first, then the coloured ones from the smallest so that the
// largest view does not hide the others.
void DrawPoints(cv::Mat& canvas, const BlurFitData& data) {
  cv::Mat left_roi = data.left.Roi(canvas);
  cv::Mat right_roi = data.right.Roi(canvas);
  for (int pass = 0; pass < 2; ++pass) {
    for (auto it = data.order.rbegin(); it != data.order.rend(); ++it) {
      const int view = it->second;
      const cv::Scalar& colour = data.colour.at(view);
      const bool grey = colour == kOtherViewsColour;
      if (grey != (pass == 0)) continue;
      for (const BlurPoint& p : data.by_view.at(view)) {
        if (Finite(p.inv_depth)) {
          DrawDot(left_roi,
                  data.left.ToLocal(p.inv_depth, p.measured),
                  2.8,
                  colour);
        }
        if (Finite(p.predicted)) {
          DrawDot(right_roi,
                  data.right.ToLocal(p.predicted, p.measured),
                  2.8,
                  colour);
        }
      }
    }
  }
}

// Frames over the points, and what an empty panel lacks.
void DrawPanelFrames(cv::Mat& canvas, const BlurFitData& data) {
  cv::rectangle(canvas, data.left.area, kAxisColour, 1);
  cv::rectangle(canvas, data.right.area, kAxisColour, 1);
  if (!data.have_left) {
    plot::DrawNoData(canvas, data.left.area, "no patch with a depth");
  }
  if (!data.have_right) {
    plot::DrawNoData(canvas,
                     data.right.area,
                     "no predicted radii (no scale or focus distances)");
  }
}

std::vector<LegendEntry> BlurFitLegendEntries(const DPScaleResult& result,
                                              const BlurFitData& data) {
  std::vector<LegendEntry> entries;
  for (size_t i = 0; i < data.order.size() && i < kNumPaletteColours; ++i) {
    const int view = data.order[i].second;
    entries.push_back({plot::ViewName(result, view) + " (" +
                           std::to_string(-data.order[i].first) + ")",
                       data.colour.at(view),
                       Glyph::kLineAndDot});
  }
  if (data.num_other_views > 0) {
    entries.push_back({std::to_string(data.num_other_views) + " more views (" +
                           std::to_string(data.num_other_points) + ")",
                       kOtherViewsColour,
                       Glyph::kDot});
  }
  if (data.have_right) {
    entries.push_back(
        {"y = x (perfect fit)", cv::Scalar(0, 0, 0), Glyph::kLine});
  }
  return entries;
}

// Legend under the panels, in four columns.
void DrawBlurFitLegend(cv::Mat& canvas,
                       const std::vector<LegendEntry>& entries) {
  const int columns = 4, column_width = (canvas.cols - 60) / columns;
  const int legend_top = 614;
  for (size_t i = 0; i < entries.size(); ++i) {
    const int x = 30 + static_cast<int>(i % columns) * column_width;
    const int y = legend_top + static_cast<int>(i / columns) * 25;
    plot::DrawGlyph(canvas, entries[i], cv::Point2d(x, y));
    PutText(canvas,
            plot::Ellipsize(entries[i].label, 0.45, 1, column_width - 42),
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
}

}  // namespace

cv::Mat RenderBlurFitPlot(const DPScaleResult& result) {
  cv::Mat canvas(700, kWidth, CV_8UC3, plot::kWhite);
  const BlurFitData data = PrepareBlurFit(result);
  DrawPanelAxes(canvas, data);
  DrawReferenceLines(canvas, data);
  DrawModelLines(canvas, data);
  DrawPoints(canvas, data);
  DrawPanelFrames(canvas, data);
  DrawBlurFitLegend(canvas, BlurFitLegendEntries(result, data));
  return plot::WithHeader(canvas,
                          kHeaderRows,
                          plot::FailureAlert(result),
                          TitleOf(data),
                          BlurFitSubtitle(data));
}

bool WriteBlurFitPlot(const DPScaleResult& result,
                      const std::string& path,
                      std::string* error) {
  return plot::RenderPng(
      [&result] { return RenderBlurFitPlot(result); }, path, error);
}

std::string BlurFitTitle(const DPScaleResult& result) {
  return TitleOf(PrepareBlurFit(result));
}

BlurFitPanels BlurFitAxes(const DPScaleResult& result) {
  BlurFitData data = PrepareBlurFit(result);
  // Where the panels are in the picture: below a header that may have grown.
  const int growth = plot::HeaderRows(kWidth,
                                      kHeaderRows,
                                      plot::FailureAlert(result),
                                      TitleOf(data),
                                      BlurFitSubtitle(data)) -
                     kHeaderRows;
  data.left.area.y += growth;
  data.right.area.y += growth;
  return {data.left, data.right};
}

}  // namespace dpsfm
