#include "dpsfm/colmap/report/loss_curve_plot.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <utility>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "dpsfm/colmap/report/plot_canvas.h"
#include "dpsfm/colmap/report/plot_legend.h"
#include "dpsfm/colmap/report/plot_result.h"
#include "dpsfm/colmap/report/plot_text.h"
#include "dpsfm/colmap/report/refusal_text.h"

namespace dpsfm {
namespace {

using plot::Axes;
using plot::DrawSegment;
using plot::Finite;
using plot::FormatValue;
using plot::Glyph;
using plot::kNaN;
using plot::LegendEntry;
using plot::Range;

const cv::Scalar kBandColour(250, 228, 205);
const cv::Scalar kBandEdgeColour(230, 190, 150);
const cv::Scalar kCurveColour(60, 60, 60);
const cv::Scalar kFinalColour(170, 90, 20);
const cv::Scalar kLinearColour(20, 130, 250);
const cv::Scalar kMinimumColour(50, 40, 215);
// Where the plot area starts (the header's rows end 12 px above it) and
// where the status under it starts.
constexpr int kAxesTop = 100;
constexpr int kHeaderRows = kAxesTop - 12;
constexpr int kWidth = 1000;  // the picture's
constexpr int kStatusTop = 588;

// The cues' bars (no curve: the cues decided).
const cv::Scalar kDpCueColour(189, 103, 148);
const cv::Scalar kFocusCueColour(44, 160, 44);

// (scale, loss) points of the curve.
using Curve = std::vector<std::pair<double, double>>;

// What the picture shows, worked out before anything is drawn.
struct LossCurveData {
  Curve curve;
  bool have_curve = false;
  bool have_final = false;         // a successful estimate's scale
  bool have_ci = false;            // and its interval
  bool have_linear = false;        // the linear estimate s*
  bool have_minimum = false;       // the curve's minimiser
  bool have_intensity_ci = false;  // and its interval
  bool have_x = false;             // any scale at all
  // No curve, and a cue to show: the cues that decided, as bars.
  bool show_cues = false;
  // The curve's height at the minimiser.
  double minimum_loss = kNaN;
  Axes axes;
};

// Curve sorted by scale (the core sorts it, but the picture must not depend
// on that), finite points only.
Curve SortedCurve(const DPScaleResult& result) {
  Curve curve;
  const size_t n = std::min(result.intensity.candidate_scales.size(),
                            result.intensity.candidate_losses.size());
  for (size_t i = 0; i < n; ++i) {
    if (Finite(result.intensity.candidate_scales[i]) &&
        Finite(result.intensity.candidate_losses[i])) {
      curve.emplace_back(result.intensity.candidate_scales[i],
                         result.intensity.candidate_losses[i]);
    }
  }
  std::sort(curve.begin(), curve.end());
  return curve;
}

// A cue the picture can draw: valid (as the report's cues) with finite
// numbers.
bool CueShown(const ScaleCue& cue) {
  return cue.valid && Finite(cue.scale) && Finite(cue.ci_low) &&
         Finite(cue.ci_high) && cue.ci_high >= cue.ci_low;
}

// One bar of the cue panel: a cue, or the answer formed from them.
struct CueBar {
  std::string label;
  double scale, ci_low, ci_high;
  cv::Scalar colour;
};

// The bars, top to bottom: the DP data's cue, the recorded focus's, and the
// answer with its interval (a successful estimate only). Numbers as the
// report's cues, scale and scale_ci_low/high.
std::vector<CueBar> CueBars(const DPScaleResult& result) {
  std::vector<CueBar> bars;
  auto interval = [](double low, double high) {
    return ", 95 % interval [" + FormatValue(low) + ", " + FormatValue(high) +
           "]";
  };
  if (CueShown(result.cues.dp)) {
    const ScaleCue& c = result.cues.dp;
    bars.push_back(
        {"DP data: s = " + FormatValue(c.scale) + interval(c.ci_low, c.ci_high),
         c.scale,
         c.ci_low,
         c.ci_high,
         kDpCueColour});
  }
  if (CueShown(result.cues.focus)) {
    const ScaleCue& c = result.cues.focus;
    std::string label = "recorded focus: s = " + FormatValue(c.scale) +
                        interval(c.ci_low, c.ci_high);
    if (c.num_views > 0) {
      label += " (" + std::to_string(c.num_views) + " view" +
               (c.num_views == 1 ? ")" : "s)");
    }
    bars.push_back({label, c.scale, c.ci_low, c.ci_high, kFocusCueColour});
  }
  if (result.success && Finite(result.scale) && Finite(result.scale_ci_low) &&
      Finite(result.scale_ci_high)) {
    std::string label = "answer: s = " + FormatValue(result.scale) +
                        interval(result.scale_ci_low, result.scale_ci_high);
    if (!result.cues.source.empty()) {
      label += " (from " + result.cues.source + ")";
    }
    bars.push_back({label,
                    result.scale,
                    result.scale_ci_low,
                    result.scale_ci_high,
                    kFinalColour});
  }
  return bars;
}

void SetFlags(const DPScaleResult& result, LossCurveData* data) {
  data->have_curve = !data->curve.empty();
  data->have_final = result.success && Finite(result.scale);
  data->have_ci = data->have_final && Finite(result.scale_ci_low) &&
                  Finite(result.scale_ci_high) &&
                  result.scale_ci_high >= result.scale_ci_low;
  data->have_linear = Finite(result.scale_initial) && result.scale_initial != 0;
  data->have_minimum = data->have_curve && Finite(result.intensity.scale) &&
                       result.intensity.scale != 0;
  data->have_intensity_ci = data->have_minimum &&
                            Finite(result.intensity.ci_low) &&
                            Finite(result.intensity.ci_high) &&
                            result.intensity.ci_high >= result.intensity.ci_low;
  data->show_cues = !data->have_curve &&
                    (CueShown(result.cues.dp) || CueShown(result.cues.focus));
}

// Scales and losses to show, padded; sets have_x.
void SetRanges(const DPScaleResult& result, LossCurveData* data) {
  Range& x_range = data->axes.x;
  Range& y_range = data->axes.y;
  for (const auto& p : data->curve) {
    x_range.Add(p.first);
    y_range.Add(p.second);
  }
  if (data->have_linear) x_range.Add(result.scale_initial);
  if (data->have_final) x_range.Add(result.scale);
  if (data->have_ci) {
    x_range.Add(result.scale_ci_low);
    x_range.Add(result.scale_ci_high);
  }
  if (data->have_minimum) x_range.Add(result.intensity.scale);
  if (data->show_cues) {
    for (const CueBar& bar : CueBars(result)) {
      x_range.Add(bar.ci_low);
      x_range.Add(bar.ci_high);
    }
  }
  data->have_x = x_range.Valid();
  // Without a curve only a few vertical lines are left: wider margins keep
  // them from filling the panel.
  plot::PadRange(&x_range,
                 data->have_curve ? 0.03 : (data->show_cues ? 0.08 : 0.5));
  plot::PadRange(&y_range, 0.08);
  // Headroom above the curve for the legend (its ends rise highest).
  if (data->have_curve) {
    y_range.hi = y_range.lo + (y_range.hi - y_range.lo) / 0.7;
  }
}

// The minimiser at the curve's height (linear interpolation; the core
// refines the minimum between candidates), the end's height beyond them.
double CurveHeightAt(const Curve& curve, double s) {
  if (s <= curve.front().first) return curve.front().second;
  if (s >= curve.back().first) return curve.back().second;
  for (size_t i = 0; i + 1 < curve.size(); ++i) {
    if (s >= curve[i].first && s <= curve[i + 1].first) {
      const double span = curve[i + 1].first - curve[i].first;
      const double f = span > 0 ? (s - curve[i].first) / span : 0;
      return curve[i].second + f * (curve[i + 1].second - curve[i].second);
    }
  }
  return kNaN;
}

// The curve, what to show and where; the plot area sits below the header
// (which grows the picture when it needs more room: plot::WithHeader).
LossCurveData PrepareLossCurve(const DPScaleResult& result) {
  LossCurveData data;
  data.curve = SortedCurve(result);
  SetFlags(result, &data);
  SetRanges(result, &data);
  if (data.have_minimum) {
    data.minimum_loss = CurveHeightAt(data.curve, result.intensity.scale);
  }
  data.axes.area = cv::Rect(105, kAxesTop, 860, 530 - kAxesTop);
  return data;
}

// The cues' names in words ("the DP data and the recorded focus").
std::string CueNames(const DPScaleResult& result) {
  const bool dp = CueShown(result.cues.dp), focus = CueShown(result.cues.focus);
  if (dp && focus) return "the DP data and the recorded focus";
  return dp ? "the DP data" : (focus ? "the recorded focus" : "");
}

std::string TitleOf(const DPScaleResult& result, const LossCurveData& data) {
  if (data.show_cues) {
    const bool both = CueShown(result.cues.dp) && CueShown(result.cues.focus);
    std::string title = result.success
                            ? (both ? "The answer from two cues: "
                                    : "The answer from one cue: ")
                            : (both ? "The two cues, which gave no answer: "
                                    : "The one cue, which gave no answer: ");
    return title + CueNames(result) + " (no intensity loss curve)";
  }
  std::string title = "Intensity loss over candidate scales";
  if (!result.intensity.loss.empty()) {
    title += " (loss: " + result.intensity.loss + ")";
  }
  return title;
}

// Where the final scale came from, in brackets ("" when unknown): the cues
// first, because the answer they form replaces what the stages gave.
std::string AnswerSource(const DPScaleResult& result,
                         const LossCurveData& data) {
  if (result.cues.combined && result.cues.agreement != CueAgreement::kOneCue) {
    return result.cues.agreement == CueAgreement::kAgree
               ? " (DP data and recorded focus combined; they agree)"
               : " (DP data and recorded focus combined; they disagree)";
  }
  if (result.cues.scale_from_recorded_focus)
    return " (from the recorded focus)";
  if (result.intensity.used) return " (intensity stage adopted)";
  if (data.have_linear && result.scale == result.scale_initial) {
    return " (linear estimate kept)";
  }
  if (!result.cues.source.empty()) return " (from " + result.cues.source + ")";
  return "";
}

std::string SubtitleOf(const DPScaleResult& result, const LossCurveData& data) {
  std::ostringstream subtitle;
  if (data.show_cues) {
    // Each cue with its interval, then what they gave.
    std::vector<std::string> cues;
    for (const auto& [name, cue] :
         {std::make_pair("DP data", &result.cues.dp),
          std::make_pair("recorded focus", &result.cues.focus)}) {
      if (!CueShown(*cue)) continue;
      cues.push_back(std::string(name) + " s = " + FormatValue(cue->scale) +
                     " [" + FormatValue(cue->ci_low) + ", " +
                     FormatValue(cue->ci_high) + "]");
    }
    subtitle << cues[0];
    if (cues.size() > 1) subtitle << " and " << cues[1];
    if (data.have_final) {
      subtitle << (cues.size() > 1 ? " give" : " gives")
               << " final s = " << plot::ScaleText(result.scale);
      if (data.have_ci) {
        subtitle << ", interval [" << FormatValue(result.scale_ci_low) << ", "
                 << FormatValue(result.scale_ci_high) << "]";
      }
      subtitle << AnswerSource(result, data);
    } else {
      if (cues.size() > 1 && result.cues.agreement == CueAgreement::kDisagree) {
        subtitle << " (they disagree)";
      }
      subtitle << "; no scale reported";
    }
    return subtitle.str();
  }
  if (data.have_final) {
    subtitle << "final s = " << plot::ScaleText(result.scale);
    if (data.have_ci) {
      subtitle << ", interval [" << FormatValue(result.scale_ci_low) << ", "
               << FormatValue(result.scale_ci_high) << "]";
    }
    subtitle << AnswerSource(result, data);
  } else if (data.have_linear) {
    subtitle << "linear estimate s* = "
             << plot::ScaleText(result.scale_initial);
  }
  return subtitle.str();
}

// The cues as horizontal interval bars (end caps, a dot at the estimate),
// one row each, labelled above the bar.
void DrawCueBars(cv::Mat& canvas,
                 const DPScaleResult& result,
                 const LossCurveData& data) {
  const std::vector<CueBar> bars = CueBars(result);
  const Axes& axes = data.axes;
  cv::Mat roi = axes.Roi(canvas);
  const double row = axes.area.height / (bars.size() + 1.0);
  for (size_t i = 0; i < bars.size(); ++i) {
    const CueBar& bar = bars[i];
    const double y = row * (i + 1) + 12;
    const double a = axes.ToLocal(bar.ci_low, 0).x;
    const double b = axes.ToLocal(bar.ci_high, 0).x;
    const double m = axes.ToLocal(bar.scale, 0).x;
    DrawSegment(roi, {a, y}, {b, y}, bar.colour, 6);
    DrawSegment(roi, {a, y - 11}, {a, y + 11}, bar.colour, 2);
    DrawSegment(roi, {b, y - 11}, {b, y + 11}, bar.colour, 2);
    plot::DrawDot(roi, {m, y}, 8, bar.colour);
    plot::DrawDot(roi, {m, y}, 8, cv::Scalar(0, 0, 0), 1);
    plot::PutText(canvas,
                  plot::Ellipsize(bar.label, 0.5, 1, axes.area.width - 20),
                  {axes.area.x + 10, axes.area.y + static_cast<int>(y) - 20},
                  0.5,
                  plot::kTextColour,
                  1);
  }
}

// The final interval as a band, drawn first so that grid and curve are drawn
// over it.
void DrawIntervalBand(cv::Mat& canvas,
                      const DPScaleResult& result,
                      const Axes& axes) {
  const double a = axes.ToPixel(result.scale_ci_low, 0).x;
  const double b = axes.ToPixel(result.scale_ci_high, 0).x;
  const int x0 = static_cast<int>(std::floor(std::min(a, b)));
  const int x1 = std::max(x0 + 2, static_cast<int>(std::ceil(std::max(a, b))));
  const cv::Rect band =
      cv::Rect(x0, axes.area.y, x1 - x0, axes.area.height) & axes.area;
  if (band.area() > 0) canvas(band).setTo(kBandColour);
}

// The band's edges, over the grid.
void DrawIntervalEdges(cv::Mat& canvas,
                       const DPScaleResult& result,
                       const Axes& axes) {
  cv::Mat roi = axes.Roi(canvas);
  for (const double scale : {result.scale_ci_low, result.scale_ci_high}) {
    const double x = axes.ToPixel(scale, 0).x - axes.area.x;
    DrawSegment(
        roi, {x, 0.0}, {x, double(axes.area.height)}, kBandEdgeColour, 1);
  }
}

// With the curve: the linear estimate where the search started (dashed,
// underneath) and the final scale over it (solid). The cues' panel has
// both as bars.
void DrawScaleLines(cv::Mat& canvas,
                    const DPScaleResult& result,
                    const LossCurveData& data) {
  if (data.show_cues) return;
  cv::Mat roi = data.axes.Roi(canvas);
  const double h = data.axes.area.height;
  if (data.have_linear) {
    const double x = data.axes.ToLocal(result.scale_initial, 0).x;
    DrawSegment(roi, {x, 0.0}, {x, h}, kLinearColour, 2, true);
  }
  if (data.have_final) {
    const double x = data.axes.ToLocal(result.scale, 0).x;
    DrawSegment(roi, {x, 0.0}, {x, h}, kFinalColour, 2);
  }
}

void DrawCurve(cv::Mat& canvas, const LossCurveData& data) {
  cv::Mat roi = data.axes.Roi(canvas);
  const Curve& curve = data.curve;
  for (size_t i = 0; i + 1 < curve.size(); ++i) {
    DrawSegment(roi,
                data.axes.ToLocal(curve[i].first, curve[i].second),
                data.axes.ToLocal(curve[i + 1].first, curve[i + 1].second),
                kCurveColour,
                2);
  }
  // Candidate dots only where they are far enough apart to be seen as such;
  // denser ones would just make the line lumpy.
  if (curve.size() * 12 <= static_cast<size_t>(data.axes.area.width)) {
    for (const auto& p : curve) {
      plot::DrawDot(
          roi, data.axes.ToLocal(p.first, p.second), 2.2, kCurveColour);
    }
  }
}

// The minimiser as a diamond on the curve, with its interval as a bar.
void DrawMinimum(cv::Mat& canvas,
                 const DPScaleResult& result,
                 const LossCurveData& data) {
  cv::Mat roi = data.axes.Roi(canvas);
  const cv::Point2d m =
      data.axes.ToLocal(result.intensity.scale, data.minimum_loss);
  if (data.have_intensity_ci) {
    const double a = data.axes.ToLocal(result.intensity.ci_low, 0).x;
    const double b = data.axes.ToLocal(result.intensity.ci_high, 0).x;
    DrawSegment(roi, {a, m.y}, {b, m.y}, kMinimumColour, 2);
    DrawSegment(roi, {a, m.y - 7}, {a, m.y + 7}, kMinimumColour, 2);
    DrawSegment(roi, {b, m.y - 7}, {b, m.y + 7}, kMinimumColour, 2);
  }
  plot::DrawDiamond(roi, m, 8, kMinimumColour, cv::Scalar(0, 0, 0));
}

// A boxed message in the middle of the area: why there is no curve.
void DrawNoCurve(cv::Mat& canvas,
                 const DPScaleResult& result,
                 const LossCurveData& data) {
  std::string message = "No intensity loss curve: ";
  message += result.intensity.status.empty()
                 ? std::string("the intensity stage was skipped")
                 : result.intensity.status;
  if (!data.have_x) message += " (and no scale to show)";
  const cv::Rect& area = data.axes.area;
  const cv::Rect box(
      area.x + area.width / 2 - 300, area.y + area.height / 2 - 50, 600, 100);
  cv::rectangle(canvas, box, cv::Scalar(245, 245, 245), cv::FILLED);
  cv::rectangle(canvas, box, cv::Scalar(180, 180, 180), 1);
  plot::DrawNoData(canvas, box, message);
}

std::vector<LegendEntry> LossCurveLegendEntries(const DPScaleResult& result,
                                                const LossCurveData& data) {
  std::vector<LegendEntry> entries;
  if (data.have_curve) {
    entries.push_back(
        {"loss (" + std::to_string(data.curve.size()) + " candidate scales)",
         kCurveColour,
         Glyph::kLineAndDot});
  }
  if (data.have_minimum) {
    entries.push_back(
        {"loss minimum s = " + FormatValue(result.intensity.scale) +
             (data.have_intensity_ci ? " (bar: its interval)" : ""),
         kMinimumColour,
         Glyph::kDiamond});
  }
  if (data.have_linear && !data.show_cues) {
    entries.push_back(
        {"linear estimate s* = " + FormatValue(result.scale_initial) +
             " (the search's start)",
         kLinearColour,
         Glyph::kDashedLine});
  }
  if (data.have_final && !data.show_cues) {
    entries.push_back(
        {"final s = " + FormatValue(result.scale), kFinalColour, Glyph::kLine});
  }
  if (data.have_ci) {
    entries.push_back({"final interval [" + FormatValue(result.scale_ci_low) +
                           ", " + FormatValue(result.scale_ci_high) + "]",
                       kBandColour,
                       Glyph::kBand});
  }
  return entries;
}

// The legend box of `size` in the corner of the plot area where the curve
// is least (never over the minimiser).
cv::Rect LegendPlace(const DPScaleResult& result,
                     const LossCurveData& data,
                     const cv::Size& size) {
  const cv::Rect& a = data.axes.area;
  const std::vector<cv::Point> corners = {
      {a.x + a.width - size.width - 10, a.y + 10},
      {a.x + 10, a.y + 10},
      {a.x + a.width - size.width - 10, a.y + a.height - size.height - 10},
      {a.x + 10, a.y + a.height - size.height - 10}};
  int best = 0, best_count = std::numeric_limits<int>::max();
  for (size_t c = 0; c < corners.size(); ++c) {
    const cv::Rect candidate(corners[c], size);
    int count = 0;
    for (const auto& p : data.curve) {
      if (candidate.contains(data.axes.ToPixel(p.first, p.second))) ++count;
    }
    if (data.have_minimum && candidate.contains(data.axes.ToPixel(
                                 result.intensity.scale, data.minimum_loss))) {
      count += 1000;
    }
    if (count < best_count) {
      best_count = count;
      best = static_cast<int>(c);
    }
  }
  return cv::Rect(corners[best], size);
}

void DrawLossCurveLegend(cv::Mat& canvas,
                         const DPScaleResult& result,
                         const LossCurveData& data) {
  const std::vector<LegendEntry> entries = LossCurveLegendEntries(result, data);
  if (entries.empty()) return;
  const cv::Size size = plot::LegendBox(entries, {0, 0}).size();
  plot::DrawLegend(canvas, entries, LegendPlace(result, data, size));
}

// Status of the intensity stage, in words, under the plot.
std::string StatusText(const DPScaleResult& result, const LossCurveData& data) {
  std::string status = result.intensity.used
                           ? "Intensity stage (adopted): "
                           : "Intensity stage (not adopted): ";
  status += result.intensity.status.empty() ? std::string("no status")
                                            : result.intensity.status;
  if (data.have_minimum && Finite(result.intensity.bootstrap_support)) {
    status += " (bootstrap support " +
              plot::Format("%.0f", 100 * result.intensity.bootstrap_support) +
              " %)";
  }
  if (data.show_cues) {
    const std::string how = CombinationText(result);
    status += ". No intensity loss curve";
    if (!how.empty()) status += "; the answer: " + how;
  }
  return status;
}

// Rows the header takes above the body's kHeaderRows (0 when it fits).
int HeaderGrowth(const DPScaleResult& result, const LossCurveData& data) {
  return plot::HeaderRows(kWidth,
                          kHeaderRows,
                          plot::FailureAlert(result),
                          TitleOf(result, data),
                          SubtitleOf(result, data)) -
         kHeaderRows;
}

}  // namespace

cv::Mat RenderLossCurvePlot(const DPScaleResult& result) {
  cv::Mat canvas(700, kWidth, CV_8UC3, plot::kWhite);
  const LossCurveData data = PrepareLossCurve(result);
  if (data.have_ci) DrawIntervalBand(canvas, result, data.axes);
  plot::DrawAxes(canvas,
                 data.axes,
                 "scale s (metres per model unit)",
                 data.have_curve ? "loss" : "",
                 data.have_x,
                 data.have_curve);
  if (data.have_ci) DrawIntervalEdges(canvas, result, data.axes);
  DrawScaleLines(canvas, result, data);
  DrawCurve(canvas, data);
  if (data.have_minimum) DrawMinimum(canvas, result, data);
  cv::rectangle(canvas, data.axes.area, plot::kAxisColour, 1);
  if (data.show_cues) {
    DrawCueBars(canvas, result, data);
  } else if (!data.have_curve) {
    DrawNoCurve(canvas, result, data);
  }
  DrawLossCurveLegend(canvas, result, data);
  const cv::Mat with_status =
      plot::WithFooter(canvas, kStatusTop, StatusText(result, data), 0.52, 24);
  return plot::WithHeader(with_status,
                          kHeaderRows,
                          plot::FailureAlert(result),
                          TitleOf(result, data),
                          SubtitleOf(result, data));
}

bool WriteLossCurvePlot(const DPScaleResult& result,
                        const std::string& path,
                        std::string* error) {
  return plot::RenderPng(
      [&result] { return RenderLossCurvePlot(result); }, path, error);
}

plot::Axes LossCurveAxes(const DPScaleResult& result) {
  const LossCurveData data = PrepareLossCurve(result);
  plot::Axes axes = data.axes;
  axes.area.y += HeaderGrowth(result, data);
  return axes;
}

std::string LossCurveTitle(const DPScaleResult& result) {
  return TitleOf(result, PrepareLossCurve(result));
}

std::string LossCurveSubtitle(const DPScaleResult& result) {
  return SubtitleOf(result, PrepareLossCurve(result));
}

bool LossCurveShowsCues(const DPScaleResult& result) {
  return PrepareLossCurve(result).show_cues;
}

}  // namespace dpsfm
