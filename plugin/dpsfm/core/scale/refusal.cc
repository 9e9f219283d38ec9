#include "dpsfm/core/scale/refusal.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <sstream>

#include "dpsfm/core/blur/blur_estimation.h"
#include "dpsfm/core/blur/patch_selection.h"
#include "dpsfm/core/scale/view_patches.h"

namespace dpsfm {

std::string CountsToString(
    const std::vector<std::pair<std::string, int>>& counts) {
  std::ostringstream s;
  bool first = true;
  for (const auto& c : counts) {
    s << (first ? "" : ", ") << c.second << " " << c.first;
    first = false;
  }
  return s.str();
}

PatchAccount AccountPatches(const std::vector<ViewPatchCounts>& views) {
  PatchAccount account;
  std::map<std::string, int> rejections;
  for (const ViewPatchCounts& v : views) {
    account.tried += v.tried;
    account.usable += v.usable;
    account.max_radius_px = std::max(account.max_radius_px, v.max_radius_px);
    for (const auto& r : v.rejections) {
      if (r.first == kLeftUnsearched) continue;
      rejections[r.first] += r.second;
    }
  }
  account.rejections.assign(rejections.begin(), rejections.end());
  const auto count_of = [&](const char* reason) {
    const auto it = rejections.find(reason);
    return it == rejections.end() ? 0 : it->second;
  };
  account.at_search_bound = count_of(kBlurAtSearchBound);
  account.texture_too_weak = count_of(kTextureTooWeak);
  return account;
}

bool PatchAccount::TextureLeads() const {
  return texture_too_weak > 0 && texture_too_weak >= 0.5 * tried;
}

bool PatchAccount::SearchBoundLimits() const {
  return tried > 0 && !(at_search_bound < 0.05 * tried) && max_radius_px > 0;
}

bool BoundAtProfileCoverage(double bound_px, double covered_px) {
  return covered_px > 0 && bound_px >= 2 * covered_px - 0.5;
}

bool PatchAccount::BoundAtProfileCoverage() const {
  return dpsfm::BoundAtProfileCoverage(max_radius_px,
                                       profile_covered_radius_px);
}

int PatchAccount::LargerSearchBound() const {
  return static_cast<int>(std::ceil(dpsfm::LargerSearchBound(max_radius_px)));
}

bool DPScaleRefusal::SmallBlurRangeOpenProfile() const {
  return code == ScaleRefusal::kLinearStageFailed &&
         !linear_failure.view_rejections.empty() &&
         linear_failure.view_rejections.front().second ==
             ViewRejection::kSmallBlurRange &&
         !(blur_read_factor <= 1.5);
}

const char* ScaleRefusalName(ScaleRefusal code) {
  switch (code) {
    case ScaleRefusal::kNone:
      return "none";
    case ScaleRefusal::kNoViews:
      return "no DP views";
    case ScaleRefusal::kLinearStageThrew:
      return "the linear stage threw";
    case ScaleRefusal::kTranslatingDiskRejected:
      return "the DP data reject the translating disk";
    case ScaleRefusal::kLinearStageFailed:
      return "the linear stage found no scale";
    case ScaleRefusal::kScaleOpen:
      return "the DP data leave the scale open";
    case ScaleRefusal::kCuesNotCombined:
      return "the DP data and the recorded focus do not combine";
  }
  return "?";
}

}  // namespace dpsfm
