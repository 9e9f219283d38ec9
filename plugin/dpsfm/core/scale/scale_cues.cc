#include "dpsfm/core/scale/scale_cues.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>
#include <stdexcept>

namespace dpsfm {
namespace {

constexpr double kZ95 = 1.959964;

// The log-scale sigma of a 95 % interval.
double LogSigma(const ScaleCue& cue) {
  return (std::log(cue.ci_high) - std::log(cue.ci_low)) / (2 * kZ95);
}

std::string Describe(const char* name, const ScaleCue& cue) {
  std::ostringstream s;
  s << std::setprecision(4) << name << " " << cue.scale << " [" << cue.ci_low
    << ", " << cue.ci_high << "]";
  return s.str();
}

}  // namespace

CombinedScale CombineScaleCues(const ScaleCue& dp, const ScaleCue& focus) {
  CombinedScale out;
  if (!dp.valid && !focus.valid) {
    throw std::invalid_argument("CombineScaleCues: no valid cue");
  }
  if (!focus.valid || !dp.valid) {
    const ScaleCue& only = dp.valid ? dp : focus;
    out.scale = only.scale;
    out.ci_low = only.ci_low;
    out.ci_high = only.ci_high;
    out.agreement = CueAgreement::kOneCue;
    out.source = dp.valid ? "DP data" : "recorded focus";
    out.how = dp.valid ? "the DP data alone (no recorded focus to combine)"
                       : "the recorded focus alone (the DP data leave the "
                         "scale open)";
    return out;
  }
  out.source = "DP data and recorded focus";
  std::ostringstream how;
  how << std::setprecision(4);
  const double sigma_dp = LogSigma(dp), sigma_focus = LogSigma(focus);
  // How far apart the estimates are, in sigmas of their difference.
  const double z = std::abs(std::log(dp.scale) - std::log(focus.scale)) /
                   std::hypot(sigma_dp, sigma_focus);
  // Consistent: either interval holds the other's estimate, or the
  // difference passes its own 95 % test. Intervals that merely touch are
  // not enough: a narrow cue that is wrong (a profile taken on trust) can
  // reach into a wide one's edge, and fusing them would answer with the
  // narrow one's error (scale_estimator_test, the sharper split).
  const bool holds = dp.Contains(focus.scale) || focus.Contains(dp.scale);
  if (holds || z <= kZ95) {
    out.agreement = CueAgreement::kAgree;
    const double wd = 1 / (sigma_dp * sigma_dp);
    const double wf = 1 / (sigma_focus * sigma_focus);
    const double mean =
        (wd * std::log(dp.scale) + wf * std::log(focus.scale)) / (wd + wf);
    const double sigma = 1 / std::sqrt(wd + wf);
    out.scale = std::exp(mean);
    out.ci_low = std::exp(mean - kZ95 * sigma);
    out.ci_high = std::exp(mean + kZ95 * sigma);
    how << "the cues agree (" << Describe("DP", dp) << ", "
        << Describe("recorded focus", focus)
        << ": "
        << (holds ? "one interval holds the other's estimate"
                : "estimates within the 95 % range of their difference")
        << "): their inverse-variance mean in log scale, with its interval";
  } else {
    out.agreement = CueAgreement::kDisagree;
    out.scale = std::sqrt(dp.scale * focus.scale);
    out.ci_low = std::min(dp.ci_low, focus.ci_low);
    out.ci_high = std::max(dp.ci_high, focus.ci_high);
    how << "the cues DISAGREE (" << Describe("DP", dp) << ", "
        << Describe("recorded focus", focus) << ": " << std::setprecision(2)
        << z
        << " sigmas of their difference apart, neither interval holding "
           "the other's estimate): an interval covering both, around their "
           "geometric mean";
  }
  out.how = how.str();
  return out;
}

}  // namespace dpsfm
