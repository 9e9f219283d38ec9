// Sums in lanes (core/util/lanes.h) against closed forms: every value must
// count once, whatever the count's remainder after the lanes' steps.
#include "dpsfm/core/util/lanes.h"

#include <vector>

#include <gtest/gtest.h>

namespace dpsfm {
namespace {

TEST(DotInLanes, EveryValueCountsOnce) {
  // a_i = i + 1 against 2: the sum is n (n + 1), exact in double.
  for (const size_t n : {0, 1, 3, 4, 5, 7, 8, 9, 15, 16, 17, 1089}) {
    std::vector<float> a(n), b(n, 2.0f);
    for (size_t i = 0; i < n; ++i) a[i] = static_cast<float>(i + 1);
    EXPECT_EQ(DotInLanes(a.data(), b.data(), n),
              static_cast<double>(n) * (n + 1))
        << n << " values";
  }
}

TEST(DotInLanes, ProductsAndSumsInDouble) {
  // 1 + 2^-20 squared is 1 + 2^-19 + 2^-40: the last term is lost in a
  // float product and kept in a double one.
  const float x = 1.0f + 0x1p-20f;
  const std::vector<float> a(9, x);
  const double square = static_cast<double>(x) * x;
  EXPECT_EQ(DotInLanes(a.data(), a.data(), a.size()), 9 * square);
  EXPECT_NE(square, static_cast<double>(x * x));
}

TEST(LanesTotal, AddsNeighbouringLanesFirst) {
  // (l0 + l1) + (l2 + l3): 1e16 and 1 are added to each other only where
  // they are neighbours, and 1e16 + 1 rounds to 1e16.
  const Lanes split = {1e16, 1.0, -1e16, 1.0};
  EXPECT_EQ(LanesTotal(split), 0.0);
  const Lanes paired = {1e16, -1e16, 1.0, 1.0};
  EXPECT_EQ(LanesTotal(paired), 2.0);
}

}  // namespace
}  // namespace dpsfm
