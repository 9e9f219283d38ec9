// Two cues to the scale, and how one answer is formed from them.
//
// The DP cue: the blur the DP views show against the model's depths, read
// through the DP profile (the linear and intensity stages); as uncertain as
// the profile's strength. The recorded-focus cue: where the disparity
// changes sign is the focal plane g' in model units whatever the profile,
// and a recorded focus distance puts it in metres (docs/psf-profiles.md, "The
// recorded focus"); as uncertain as the record. Each cue comes with a 95 %
// interval that is meant to own its errors; the answer never rests on one
// of two cues that disagree.
#pragma once

#include <string>

namespace dpsfm {

struct ScaleCue {
  bool valid = false;  // measured, with a finite positive interval
  double scale = 0;
  double ci_low = 0, ci_high = 0;
  int num_views = 0;  // views that carry it (recorded focus)

  bool Contains(double s) const { return s >= ci_low && s <= ci_high; }
};

enum class CueAgreement {
  kOneCue,    // only one cue was there
  kAgree,     // consistent: see CombineScaleCues
  kDisagree,  // otherwise
};

struct CombinedScale {
  double scale = 0;
  double ci_low = 0, ci_high = 0;
  CueAgreement agreement = CueAgreement::kOneCue;
  // "DP data", "recorded focus" or "DP data and recorded focus".
  std::string source;
  // How the answer was formed, for people.
  std::string how;
};

// The answer from the cues that are valid (at least one must be). Each
// 95 % interval is read as a normal in log-scale (sigma = its log width /
// 3.92):
// - one cue: its estimate and interval;
// - two that agree (either interval holds the other's estimate, or the
//   estimates lie within 1.96 sigmas of their difference): the
//   inverse-variance mean of the log-scales (independent errors: the
//   profile's transfer against the record's accuracy) and its 95 %
//   interval;
// - two that disagree: the geometric mean of the two estimates, with the
//   hull of both intervals (it holds the truth whenever either does).
// Throws std::invalid_argument when neither cue is valid.
CombinedScale CombineScaleCues(const ScaleCue& dp, const ScaleCue& focus);

}  // namespace dpsfm
