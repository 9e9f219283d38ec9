// Diagnostic pictures written next to the JSON report: people look at the
// data before they trust a number, so each plot shows what the estimate rests
// on (blur against the thin-lens model, the intensity loss curve, where the
// patches are). Drawn with OpenCV only (no plotting dependency), as PNG; the
// figures are in blur_fit_plot.h, loss_curve_plot.h and patch_overlay_plot.h,
// the drawing toolkit they share in plot_*.h.
//
// No data makes a figure throw: odd data (NaN, empty vectors, a failed
// estimate) are drawn as far as they go and said so in the picture. A picture
// that cannot be rendered or written is reported by the return value, with
// the reason, because a missing picture must never fail a run whose scale is
// fine.
#pragma once

#include <string>
#include <utility>
#include <vector>

#include <opencv2/core.hpp>

#include "dpsfm/colmap/report/blur_fit_plot.h"
#include "dpsfm/colmap/report/loss_curve_plot.h"
#include "dpsfm/colmap/report/patch_overlay_plot.h"
#include "dpsfm/core/scale/scale_estimator.h"

namespace dpsfm {

// A report picture that was not written.
struct PlotFailure {
  std::string plot;   // "blur_fit", "loss" or "patches_<view>"
  std::string path;   // where it was to be written
  std::string error;  // why not: an exception's what() or the writer's word
};

// What WriteReportPlots did: the paths written, in order, and the failures.
struct ReportPlotFiles {
  std::vector<std::string> written;
  std::vector<PlotFailure> failures;
};

// Writes <stem>_blur_fit.png, <stem>_loss.png and, for each view's picture
// in `overlay_images` (OverlayImage), <stem>_patches_<view>.png next
// to `report_path` (stem = report path without its extension; <view> = the
// view's name without its extension, every character other than
// [A-Za-z0-9._-] replaced by '_', made unique by the view index if needed;
// an empty image is skipped). `working_patch_size` is the patch side in
// working-frame pixels as in DPViewSummary::patch_size (<= 0:
// DefaultPatchGeometry of the DP frame); it is converted to DP-frame pixels
// with the view's resize factor, recovered from its patches (radius_px /
// radius_frame_px). An exception while drawing or writing one picture costs
// that picture only and is recorded among the failures. The pictures are
// drawn and written on `num_threads` threads (-1: all cores); the paths
// and failures come in the order above whatever the count.
ReportPlotFiles WriteReportPlots(
    const DPScaleResult& result,
    const std::vector<OverlayImage>& overlay_images,
    const std::string& report_path,
    int working_patch_size,
    int num_threads = 1);

// The <view> part of an overlay's file name (see WriteReportPlots).
std::string PlotFileComponent(const std::string& view_name);

}  // namespace dpsfm
