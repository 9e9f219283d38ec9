// Patch selection: the top-T_c share by confidence, and its spread over
// depth, against hand-made rankings.
#include "dpsfm/core/blur/patch_selection.h"

#include <cmath>
#include <vector>

#include <gtest/gtest.h>

namespace dpsfm {
namespace {

TEST(SelectTopFraction, KeepsBestTenPercentWithMinimum) {
  std::vector<double> conf(50);
  for (int i = 0; i < 50; ++i) conf[i] = (i * 37) % 50;
  const std::vector<int> top = SelectTopFraction(conf, 0.1, 3);
  ASSERT_EQ(top.size(), 5u);
  for (int i : top) EXPECT_GE(conf[i], 45);
  EXPECT_EQ(SelectTopFraction(conf, 0.01, 4).size(), 4u);
  conf[7] = NAN;
  for (int i : SelectTopFraction(conf, 0.98, 0)) EXPECT_NE(i, 7);
  EXPECT_TRUE(SelectTopFraction({}, 0.1, 3).empty());
}

TEST(SelectTopFractionStratified, SpreadsOverDepth) {
  // 90 patches on three planes; the nearest plane is the most textured, so a
  // plain top 10 % takes only it.
  std::vector<double> conf, key;
  for (int i = 0; i < 90; ++i) {
    const int plane = i % 3;
    key.push_back(1.0 / (1.0 + plane));
    conf.push_back((plane == 0 ? 100 : 10) + i * 0.01);
  }
  std::vector<int> plain = SelectTopFraction(conf, 0.1, 0);
  for (int i : plain) EXPECT_EQ(i % 3, 0);
  const std::vector<int> spread =
      SelectTopFractionStratified(conf, key, 0.1, 0, 4);
  ASSERT_EQ(spread.size(), plain.size());
  int per_plane[3] = {0, 0, 0};
  for (int i : spread) per_plane[i % 3]++;
  for (int p = 0; p < 3; ++p) EXPECT_EQ(per_plane[p], 3) << p;
  // strata = 1 is the plain selection.
  EXPECT_EQ(SelectTopFractionStratified(conf, key, 0.1, 0, 1), plain);
}

TEST(PatchConfidence, TextureTimesFitOverFlooredDepthVariance) {
  // 2 x 0.5 / (0.0099 + 1e-4) = 100; the 1e-4 floor (1 % depth std) rules
  // for a perfectly flat patch: 3 x 1 / 1e-4 = 30000.
  EXPECT_NEAR(PatchConfidence(2.0, 0.5, 0.0099), 100.0, 1e-9);
  EXPECT_NEAR(PatchConfidence(3.0, 1.0, 0.0), 30000.0, 1e-6);
  // Negative texture or fit quality count as nothing.
  EXPECT_EQ(PatchConfidence(-1.0, 0.5, 0.01), 0.0);
  EXPECT_EQ(PatchConfidence(1.0, -0.5, 0.01), 0.0);
}

}  // namespace
}  // namespace dpsfm
