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
// confidence interval (shaded band) and the intensity stage's status. An
// empty curve (stage skipped or failed) gives a panel that says so. About
// 1000x700. No data makes it throw; it throws only what OpenCV or an
// allocation does.
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

}  // namespace dpsfm
