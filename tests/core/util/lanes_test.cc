// Sums in lanes (core/util/lanes.h) against closed forms: every value must
// count once, whatever the count's remainder after the lanes' steps.
#include "dpsfm/core/util/lanes.h"

#include <cmath>
#include <cstdint>
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

// The vector extension's lanes and the plain ones are the same operations:
// the same bits on values whose sums round.
TEST(DotInLanes, PortableAndVectorLanesGiveTheSameBits) {
  std::vector<float> a(1091), b(1091);
  uint32_t state = 7;
  for (size_t i = 0; i < a.size(); ++i) {
    // Exponents over a wide range, so that the sums round.
    state = state * 1664525u + 1013904223u;
    a[i] = std::ldexp(static_cast<float>(state >> 8) * 0x1p-24f - 0.5f,
                      static_cast<int>(state % 61) - 30);
    state = state * 1664525u + 1013904223u;
    b[i] = static_cast<float>(state >> 8) * 0x1p-24f;
  }
  for (const size_t n : {size_t{5}, size_t{64}, size_t{1091}}) {
    const double portable = DotInLanesOf<PortableLanes>(a.data(), b.data(), n);
    const double lanes = DotInLanesOf<Lanes>(a.data(), b.data(), n);
    EXPECT_EQ(portable, lanes) << n;
    EXPECT_EQ(DotInLanes(a.data(), b.data(), n), lanes) << n;
  }
  // The sum in one chain rounds otherwise (the test can tell).
  double chain = 0;
  for (size_t i = 0; i < a.size(); ++i) chain += static_cast<double>(a[i]) * b[i];
  EXPECT_NE(chain, DotInLanes(a.data(), b.data(), a.size()));
}

TEST(LanesTotal, AddsNeighbouringLanesFirst) {
  // (l0 + l1) + (l2 + l3): 1e16 and 1 are added to each other only where
  // they are neighbours, and 1e16 + 1 rounds to 1e16.
  const Lanes split = {1e16, 1.0, -1e16, 1.0};
  EXPECT_EQ(LanesTotal(split), 0.0);
  const Lanes paired = {1e16, -1e16, 1.0, 1.0};
  EXPECT_EQ(LanesTotal(paired), 2.0);
  const PortableLanes plain_split = {1e16, 1.0, -1e16, 1.0};
  EXPECT_EQ(LanesTotal(plain_split), 0.0);
}

}  // namespace
}  // namespace dpsfm
