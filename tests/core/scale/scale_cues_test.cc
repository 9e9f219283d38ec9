#include "dpsfm/core/scale/scale_cues.h"

#include <cmath>
#include <stdexcept>

#include <gtest/gtest.h>

namespace dpsfm {
namespace {

ScaleCue Cue(double scale, double lo, double hi) {
  ScaleCue cue;
  cue.valid = true;
  cue.scale = scale;
  cue.ci_low = lo;
  cue.ci_high = hi;
  return cue;
}

TEST(CombineScaleCues, OneCueIsTakenAsItIs) {
  const CombinedScale dp = CombineScaleCues(Cue(2, 1.8, 2.3), ScaleCue());
  EXPECT_EQ(dp.agreement, CueAgreement::kOneCue);
  EXPECT_EQ(dp.source, "DP data");
  EXPECT_EQ(dp.scale, 2);
  EXPECT_EQ(dp.ci_low, 1.8);
  EXPECT_EQ(dp.ci_high, 2.3);
  const CombinedScale focus = CombineScaleCues(ScaleCue(), Cue(3, 2.5, 3.5));
  EXPECT_EQ(focus.source, "recorded focus");
  EXPECT_EQ(focus.scale, 3);
  EXPECT_EQ(focus.ci_high, 3.5);
  EXPECT_THROW(CombineScaleCues(ScaleCue(), ScaleCue()), std::invalid_argument);
}

// Two agreeing cues whose intervals have the same log width weigh the same:
// sigma = ln(1.1 / 0.9) / 3.92 = 0.051191 each, the estimates ln(1.05) =
// 0.048790 apart (0.67 sigma of the difference). The answer is the
// geometric mean sqrt(1.05) = 1.024695 with sigma / sqrt(2): exp(0.024395
// -+ 1.96 x 0.036198) = [0.954514, 1.100036].
TEST(CombineScaleCues, AgreeingCuesOfEqualWeight) {
  const CombinedScale c =
      CombineScaleCues(Cue(1.0, 0.9, 1.1), Cue(1.05, 0.945, 1.155));
  EXPECT_EQ(c.agreement, CueAgreement::kAgree);
  EXPECT_EQ(c.source, "DP data and recorded focus");
  EXPECT_NEAR(c.scale, 1.0246951, 1e-6);
  EXPECT_NEAR(c.ci_low, 0.9545142, 1e-6);
  EXPECT_NEAR(c.ci_high, 1.1000360, 1e-6);
}

// Unequal widths: DP 1.0 [0.9, 1.1] (sigma 0.051191) and focus 1.05
// [0.9, 1.2] (sigma 0.073388): weights 1 / sigma^2 = 381.6 and 185.7 give
// exp(0.048790 x 185.7 / 567.3) = 1.016098, nearer the narrower cue, with
// sigma 1 / sqrt(567.3) = 0.041985: [0.935828, 1.103252].
TEST(CombineScaleCues, AgreeingCuesWeighByTheirWidth) {
  const CombinedScale c =
      CombineScaleCues(Cue(1.0, 0.9, 1.1), Cue(1.05, 0.9, 1.2));
  EXPECT_EQ(c.agreement, CueAgreement::kAgree);
  EXPECT_NEAR(c.scale, 1.0160977, 1e-6);
  EXPECT_NEAR(c.ci_low, 0.9358282, 1e-6);
  EXPECT_NEAR(c.ci_high, 1.1032521, 1e-6);
}

// DP 0.78 [0.72, 0.80] (sigma ln(0.80 / 0.72) / 3.92 = 0.026878) and focus
// 0.95 [0.82, 1.10] (sigma 0.074947) are ln(0.95 / 0.78) = 0.197165 apart,
// 2.48 sigmas of their difference, and neither interval holds the other's
// estimate: they disagree, and the interval covers both, [0.72, 1.10],
// around sqrt(0.78 x 0.95) = 0.860814.
TEST(CombineScaleCues, DisagreeingCuesAreCoveredBoth) {
  const CombinedScale c =
      CombineScaleCues(Cue(0.78, 0.72, 0.80), Cue(0.95, 0.82, 1.10));
  EXPECT_EQ(c.agreement, CueAgreement::kDisagree);
  EXPECT_NEAR(c.scale, 0.8608136, 1e-6);
  EXPECT_DOUBLE_EQ(c.ci_low, 0.72);
  EXPECT_DOUBLE_EQ(c.ci_high, 1.10);
  EXPECT_NE(c.how.find("DISAGREE"), std::string::npos) << c.how;
  // The same the other way round.
  const CombinedScale swapped =
      CombineScaleCues(Cue(0.95, 0.82, 1.10), Cue(0.78, 0.72, 0.80));
  EXPECT_EQ(swapped.agreement, CueAgreement::kDisagree);
  EXPECT_DOUBLE_EQ(swapped.ci_low, 0.72);
  EXPECT_DOUBLE_EQ(swapped.ci_high, 1.10);
}

// DP 0.81 [0.75, 0.88] and focus 0.95 [0.82, 1.10] are 1.87 sigmas of their
// difference apart, within its 95 % range: they agree. sigma_dp =
// ln(0.88 / 0.75) / 3.92 = 0.040794, sigma_focus = ln(1.10 / 0.82) / 3.92 =
// 0.074947: the inverse-variance mean 0.840045 with [0.783093, 0.901139].
TEST(CombineScaleCues, OverlappingIntervalsAgree) {
  const CombinedScale c =
      CombineScaleCues(Cue(0.81, 0.75, 0.88), Cue(0.95, 0.82, 1.10));
  EXPECT_EQ(c.agreement, CueAgreement::kAgree);
  EXPECT_NEAR(c.scale, 0.8400452, 1e-6);
  EXPECT_NEAR(c.ci_low, 0.7830933, 1e-6);
  EXPECT_NEAR(c.ci_high, 0.9011390, 1e-6);
}

// Intervals that touch are not enough: a narrow DP cue 0.06155 [0.05989,
// 0.06321] (a wrong profile taken on trust) reaches into the focus cue's
// 0.07313 [0.062, 0.08426], but the estimates are ln(0.07313 / 0.06155) =
// 0.172389 apart, 2.17 sigmas of their difference (sigmas 0.013753 and
// 0.078207), and neither interval holds the other's estimate. Fusing them
// would answer about 0.0619 [0.0599, 0.0632], missing the focus's truth.
TEST(CombineScaleCues, TouchingIntervalsOfDistantEstimatesDisagree) {
  const CombinedScale c = CombineScaleCues(Cue(0.06155, 0.05989, 0.06321),
                                           Cue(0.07313, 0.062, 0.08426));
  EXPECT_EQ(c.agreement, CueAgreement::kDisagree);
  EXPECT_DOUBLE_EQ(c.ci_low, 0.05989);
  EXPECT_DOUBLE_EQ(c.ci_high, 0.08426);
}

// A wide cue whose estimate lies outside a narrow one's interval, but whose
// interval holds all of it, says nothing against it: the answer is nearly
// the narrow cue's (weights 1 / sigma^2: exp(ln 0.86 x 0.0402) = 0.991822,
// [0.899625, 1.093467]), not a refusal.
TEST(CombineScaleCues, NestedIntervalsAgree) {
  const CombinedScale c =
      CombineScaleCues(Cue(0.86, 0.52, 1.2), Cue(1.0, 0.9, 1.1));
  EXPECT_EQ(c.agreement, CueAgreement::kAgree);
  EXPECT_NEAR(c.scale, 0.9918216, 1e-6);
  EXPECT_NEAR(c.ci_low, 0.8996247, 1e-6);
  EXPECT_NEAR(c.ci_high, 1.0934672, 1e-6);
}

// Over a grid of cue pairs: the answer lies in its interval, which lies in
// the hull of the two; disagreeing cues are covered both, so the interval
// holds the truth whenever either cue's does; agreeing cues give an
// interval no wider than the narrower cue's.
TEST(CombineScaleCues, IntervalsOverAGridOfCues) {
  const double truth = 1.0;
  for (double d = 0.7; d <= 1.3; d += 0.05) {
    for (double f = 0.7; f <= 1.3; f += 0.05) {
      const ScaleCue dp = Cue(d, d * 0.9, d * 1.12);
      const ScaleCue focus = Cue(f, f * 0.85, f * 1.15);
      const CombinedScale c = CombineScaleCues(dp, focus);
      EXPECT_GE(c.scale, c.ci_low);
      EXPECT_LE(c.scale, c.ci_high);
      EXPECT_GE(c.ci_low, std::min(dp.ci_low, focus.ci_low) - 1e-12);
      EXPECT_LE(c.ci_high, std::max(dp.ci_high, focus.ci_high) + 1e-12);
      if (c.agreement == CueAgreement::kDisagree) {
        if (dp.Contains(truth) || focus.Contains(truth)) {
          EXPECT_LE(c.ci_low, truth) << d << " " << f;
          EXPECT_GE(c.ci_high, truth) << d << " " << f;
        }
      } else {
        EXPECT_LE(std::log(c.ci_high / c.ci_low),
                  std::log(dp.ci_high / dp.ci_low) + 1e-12);
      }
    }
  }
}

}  // namespace
}  // namespace dpsfm
