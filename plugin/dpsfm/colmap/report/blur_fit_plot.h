// The blur fit picture of the report: the measured blur of the patches
// against the thin-lens model.
#pragma once

#include <string>

#include <opencv2/core.hpp>

#include "dpsfm/colmap/report/plot_axes.h"
#include "dpsfm/core/scale/scale_estimator.h"

namespace dpsfm {

// (a) Measured blur radius of the used patches of every used view (colour
// per view, legend with view names; beyond 10 views the rest are grey),
// in DP-frame pixels. Left panel: against inverse model depth 1/z', with the
// view's thin-lens prediction under the final scale as a line (the model is
// affine in 1/z'). Right panel: against the predicted radius, with y = x.
// The title gives the report's linear_median_abs_residual_px (the linear
// stage's median |measured - fitted| in working-frame pixels under s*). Without
// used views (a failed estimate) the selected patches are shown instead. About
// 1000x700. No data makes it throw; it throws only what OpenCV or an allocation
// does.
cv::Mat RenderBlurFitPlot(const DPScaleResult& result);
// Writes RenderBlurFitPlot as PNG; false if it could not, with the reason in
// *error (if given). Never throws.
bool WriteBlurFitPlot(const DPScaleResult& result,
                      const std::string& path,
                      std::string* error = nullptr);

// Where RenderBlurFitPlot puts its panels: the plot areas in the picture and
// the data ranges they show (left: 1/z' against the measured radius, right:
// the predicted radius against the measured one). For tests and for anyone
// annotating further.
struct BlurFitPanels {
  plot::Axes left;
  plot::Axes right;
};
BlurFitPanels BlurFitAxes(const DPScaleResult& result);

// The picture's title, with the report's linear_median_abs_residual_px when
// there is one.
std::string BlurFitTitle(const DPScaleResult& result);

}  // namespace dpsfm
