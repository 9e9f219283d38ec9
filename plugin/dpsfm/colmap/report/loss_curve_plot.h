// The loss curve picture of the report: the intensity stage's loss over the
// candidate scales, with the scales the run found.
#pragma once

#include <string>

#include <opencv2/core.hpp>

#include "dpsfm/colmap/report/plot_axes.h"
#include "dpsfm/core/scale/scale_estimator.h"

namespace dpsfm {

// (b) Intensity loss over the candidate scales, the minimiser (marker), the
// linear estimate s* (dashed line), the final scale (solid line) with its
// confidence interval (shaded band) and the intensity stage's status.
// Without a curve (stage skipped or failed) the cues that decided are shown
// instead (ScaleCuesResult::dp, focus): each valid cue's scale and 95 %
// interval and the answer with its interval as horizontal bars on the scale
// axis, numbers as the report's cues, scale and scale_ci_low/high; with no
// cue either, a panel that says there is no curve. About 1000x700. No data
// makes it throw; it throws only what OpenCV or an allocation does.
cv::Mat RenderLossCurvePlot(const DPScaleResult& result);
// Writes RenderLossCurvePlot as PNG; false if it could not, with the reason
// in *error (if given). Never throws.
bool WriteLossCurvePlot(const DPScaleResult& result,
                        const std::string& path,
                        std::string* error = nullptr);

// Where RenderLossCurvePlot draws: the plot area in the picture and the
// ranges of scale (x) and loss (y) it shows. For tests and for anyone
// annotating further.
plot::Axes LossCurveAxes(const DPScaleResult& result);

// The picture's title and subtitle. The subtitle gives the final scale and
// its interval and where it came from (the cues combined, the recorded
// focus, the intensity stage, or "linear estimate kept" only when the final
// scale is the linear estimate s*); in the cues' panel, each cue's scale and
// interval first.
std::string LossCurveTitle(const DPScaleResult& result);
std::string LossCurveSubtitle(const DPScaleResult& result);
// Whether the picture shows the cues' bars (no curve, a valid cue).
bool LossCurveShowsCues(const DPScaleResult& result);

}  // namespace dpsfm
