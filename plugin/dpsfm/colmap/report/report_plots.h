// Diagnostic pictures written next to the JSON report: people look at the
// data before they trust a number, so each plot shows what the estimate rests
// on (blur against the thin-lens model, the intensity loss curve, where the
// patches are). Drawn with OpenCV only (no plotting dependency), as PNG.
//
// None of these functions throws: odd data (NaN, empty vectors, a failed
// estimate) are drawn as far as they go and said so in the picture; a file
// that cannot be written is reported by the return value only, because a
// missing picture must never fail a run whose scale is fine.
#pragma once

#include <string>
#include <utility>
#include <vector>

#include <opencv2/core.hpp>

#include "dpsfm/core/scale/scale_estimator.h"

namespace dpsfm {

// (a) Measured blur radius of the used patches of every used view (colour
// per view, legend with view names; beyond 10 views the rest are grey),
// in DP-frame pixels. Left panel: against inverse model depth 1/z', with the
// view's thin-lens prediction under the final scale as a line (the model is
// affine in 1/z'). Right panel: against the predicted radius, with y = x.
// The title gives the median |measured - predicted|. Without used views (a
// failed estimate) the selected patches are shown instead. About 1000x700.
cv::Mat RenderBlurFitPlot(const DPScaleResult& result);
bool WriteBlurFitPlot(const DPScaleResult& result, const std::string& path);

// (b) Intensity loss over the candidate scales, the minimiser (marker), the
// linear estimate s* (dashed line), the final scale (solid line) with its
// confidence interval (shaded band) and the intensity stage's status. An
// empty curve (stage skipped or failed) gives a panel that says so. About
// 1000x700.
cv::Mat RenderLossCurvePlot(const DPScaleResult& result);
bool WriteLossCurvePlot(const DPScaleResult& result, const std::string& path);

// (c) The DP image of view `view_index` (left + right or left alone;
// CV_32FC1/CV_32FC3 in [0, 1]; 8/16-bit images are accepted too) shown in
// grey with a display gamma (linear DP frames are dark), downscaled to at
// most 1600 px wide, with the view's selected patches as squares coloured by
// their signed blur radius (diverging map: blue = negative = nearer than the
// focal plane, white ~ 0, red = positive = farther), a colour bar and a
// legend. Used patches are filled with a thick border, selected-but-unused
// ones are thin outlines. `patch_size_px` is the square's side in pixels of
// `image`, which must be the DP frame the patch coordinates refer to
// (<= 0: a default size). `view_name` titles the picture; an empty one falls
// back to the result's name of the view. Returns an empty Mat for an empty
// image.
cv::Mat RenderPatchOverlay(const cv::Mat& image,
                           const std::string& view_name,
                           int view_index,
                           const DPScaleResult& result,
                           double patch_size_px);
bool WritePatchOverlay(const cv::Mat& image,
                       const std::string& view_name,
                       int view_index,
                       const DPScaleResult& result,
                       double patch_size_px,
                       const std::string& path);

// Where DP-frame pixel (x, y) of an image of `image_size` lands in the
// picture RenderPatchOverlay draws (its layout: the image is resized and
// placed below a title band). For tests and for anyone annotating further.
cv::Point2d PatchOverlayPoint(const cv::Size& image_size, double x, double y);

// Writes <stem>_blur_fit.png, <stem>_loss.png and, for each
// (view index, DP image) in `overlay_images`, <stem>_patches_<view>.png next
// to `report_path` (stem = report path without its extension; <view> = the
// view's name without its extension, every character other than
// [A-Za-z0-9._-] replaced by '_', made unique by the view index if needed).
// `working_patch_size` is the patch side in working-frame pixels as in
// DPViewSummary::patch_size (<= 0: DefaultPatchGeometry of the image); it is
// converted to DP-frame pixels with the view's resize factor, recovered from
// its patches (radius_px / radius_frame_px). Returns the paths written.
std::vector<std::string> WriteReportPlots(
    const DPScaleResult& result,
    const std::vector<std::pair<int, cv::Mat>>& overlay_images,
    const std::string& report_path,
    int working_patch_size);

// The <view> part of an overlay's file name (see WriteReportPlots).
std::string PlotFileComponent(const std::string& view_name);

}  // namespace dpsfm
