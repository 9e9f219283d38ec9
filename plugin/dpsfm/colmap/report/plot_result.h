// What the report pictures read off a DPScaleResult beyond its fields: view
// names and states, the DP-frame size of working-frame pixels, the failure
// line and label texts the figures share.
#pragma once

#include <map>
#include <optional>
#include <string>

#include <opencv2/core.hpp>

#include "dpsfm/core/blur/blur_estimation.h"
#include "dpsfm/core/scale/scale_estimator.h"

namespace dpsfm {
namespace plot {

// The view's name, or "view <index>" for an unnamed or unknown view.
std::string ViewName(const DPScaleResult& result, int view);

// Whether `view` is a view of the result that the estimate used.
bool ViewUsed(const DPScaleResult& result, int view);

// DP-frame pixels per working-frame pixel of each view, recovered from its
// patches (both radii are stored); NaN where no patch tells.
std::map<int, double> FramePerWorkingPixel(const DPScaleResult& result);

// "<scale> m/unit".
std::string ScaleText(double scale);

// "Estimate failed: <reason>" for a failed estimate, empty for a successful
// one (the header's alert, plot_text.h).
std::string FailureAlert(const DPScaleResult& result);

// DefaultPatchGeometry of a DP frame of `frame_size`; nothing for an empty
// size, which it would refuse.
std::optional<PatchGeometry> DefaultFrameGeometry(const cv::Size& frame_size);

}  // namespace plot
}  // namespace dpsfm
