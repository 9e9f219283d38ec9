// The patch overlay picture of the report: where a view's patches are and
// the signed blur measured in each.
#pragma once

#include <string>

#include <opencv2/core.hpp>

#include "dpsfm/core/scale/scale_estimator.h"

namespace dpsfm {

// (c) The DP image of view `view_index` (left + right or left alone;
// CV_32FC1/CV_32FC3 in [0, 1]; 8/16-bit images are accepted too) shown in
// grey with a display gamma (linear DP frames are dark), downscaled to at
// most 1600 px wide, with the view's selected patches as squares coloured by
// their signed blur radius (diverging map: blue = negative = nearer than the
// focal plane, white ~ 0, red = positive = farther), a colour bar and a
// legend. Used patches are filled with a thick border, selected-but-unused
// ones are thin outlines. `image` shows the whole DP frame the patch
// coordinates refer to, which is `frame_size` pixels (empty: the image's
// own size; the image may be the frame at any resolution, e.g. the working
// frame); `patch_size_px` is the square's side in pixels of that frame
// (<= 0: a default size). `view_name` titles the picture; an empty one falls
// back to the result's name of the view. Returns an empty Mat for an empty
// image. A colour image of a depth OpenCV cannot convert to grey is shown as
// a grey area. No data makes it throw; it throws only what OpenCV or an
// allocation does.
cv::Mat RenderPatchOverlay(const cv::Mat& image,
                           const std::string& view_name,
                           int view_index,
                           const DPScaleResult& result,
                           double patch_size_px,
                           const cv::Size& frame_size = cv::Size());
// Writes RenderPatchOverlay as PNG; false if it could not (an empty image
// included), with the reason in *error (if given). Never throws.
bool WritePatchOverlay(const cv::Mat& image,
                       const std::string& view_name,
                       int view_index,
                       const DPScaleResult& result,
                       double patch_size_px,
                       const std::string& path,
                       std::string* error = nullptr);

// Where DP-frame pixel (x, y) of a frame of `frame_size` lands in the
// picture RenderPatchOverlay draws (its layout: the image is resized and
// placed below a title band). For tests and for anyone annotating further.
cv::Point2d PatchOverlayPoint(const cv::Size& frame_size, double x, double y);

// A view's picture for the report's overlay (RenderPatchOverlay's image
// and frame_size).
struct OverlayImage {
  int view = -1;
  cv::Mat image;
  cv::Size frame_size;
};

}  // namespace dpsfm
