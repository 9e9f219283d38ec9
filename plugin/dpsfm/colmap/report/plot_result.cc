#include "dpsfm/colmap/report/plot_result.h"

#include <cmath>
#include <vector>

#include "dpsfm/colmap/report/plot_text.h"
#include "dpsfm/colmap/report/refusal_text.h"
#include "dpsfm/core/util/statistics.h"

namespace dpsfm {
namespace plot {

std::string ViewName(const DPScaleResult& result, int view) {
  if (view >= 0 && view < static_cast<int>(result.views.size()) &&
      !result.views[view].name.empty()) {
    return result.views[view].name;
  }
  return "view " + std::to_string(view);
}

bool ViewUsed(const DPScaleResult& result, int view) {
  return view >= 0 && view < static_cast<int>(result.views.size()) &&
         result.views[view].used;
}

std::map<int, double> FramePerWorkingPixel(const DPScaleResult& result) {
  std::map<int, std::vector<double>> ratios;
  for (const PatchSample& s : result.patches) {
    if (Finite(s.radius_px) && Finite(s.radius_frame_px) &&
        std::abs(s.radius_px) > 1e-6) {
      const double ratio = s.radius_frame_px / s.radius_px;
      if (ratio > 0 && Finite(ratio)) ratios[s.view].push_back(ratio);
    }
  }
  std::map<int, double> out;
  for (const auto& r : ratios) out[r.first] = FiniteMedian(r.second);
  return out;
}

std::string ScaleText(double scale) { return FormatValue(scale) + " m/unit"; }

std::string FailureAlert(const DPScaleResult& result) {
  if (result.success) return "";
  const std::string reason = RefusalLine(result.refusal);
  return "Estimate failed: " +
         (reason.empty() ? std::string("no reason given") : reason);
}

std::optional<PatchGeometry> DefaultFrameGeometry(const cv::Size& frame_size) {
  if (frame_size.width <= 0 || frame_size.height <= 0) return std::nullopt;
  return DefaultPatchGeometry(frame_size);
}

}  // namespace plot
}  // namespace dpsfm
