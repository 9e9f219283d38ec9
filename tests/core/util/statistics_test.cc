// Each statistic against values worked out by hand.
#include "dpsfm/core/util/statistics.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include <gtest/gtest.h>

namespace dpsfm {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

TEST(Median, OddEvenAndEmpty) {
  EXPECT_EQ(Median({5, 1, 3}), 3);
  // Even count: the mean of the two middle values, 2 and 7.
  EXPECT_EQ(Median({10, 2, 7, 1}), 4.5);
  EXPECT_TRUE(std::isnan(Median({})));
}

TEST(FiniteMedian, DropsNonFiniteValues) {
  // Finite values 1, 4, 6: median 4 (with the infinities counted it would
  // be (4 + 6) / 2 = 5).
  EXPECT_EQ(FiniteMedian({6, kNaN, 1, kInf, 4}), 4);
  EXPECT_TRUE(std::isnan(FiniteMedian({kNaN, kInf})));
}

TEST(Percentile, InterpolatesBetweenSortedValues) {
  // Sorted 10, 20, 30, 40: q = 0.5 sits at position 1.5 -> 25;
  // q = 0.9 at 2.7 -> 30 + 0.7 * 10 = 37.
  const std::vector<double> v = {40, 10, 30, 20};
  EXPECT_DOUBLE_EQ(Percentile(v, 0.5), 25);
  EXPECT_DOUBLE_EQ(Percentile(v, 0.9), 37);
  EXPECT_DOUBLE_EQ(Percentile(v, 0), 10);
  EXPECT_DOUBLE_EQ(Percentile(v, 1), 40);
  EXPECT_TRUE(std::isnan(Percentile({}, 0.5)));
}

TEST(NearestRankQuantile, PicksASample) {
  // Sorted 10, 20, 30, 40: q = 0.5 -> rank round(1.5) = 2 -> 30 (a sample,
  // unlike Percentile's 25); q = 0.2 -> rank round(0.6) = 1 -> 20.
  const std::vector<double> v = {40, 10, kNaN, 30, 20};
  EXPECT_EQ(NearestRankQuantile(v, 0.5), 30);
  EXPECT_EQ(NearestRankQuantile(v, 0.2), 20);
  EXPECT_EQ(NearestRankQuantile(v, 1), 40);
  EXPECT_TRUE(std::isnan(NearestRankQuantile({kNaN}, 0.5)));
}

TEST(RankInPlace, UpperMedianAndRanks) {
  std::vector<float> v = {4, 8, 1, 6};
  // Ranks 0..3 of {1, 4, 6, 8}; the upper median of an even count is 6.
  EXPECT_EQ(UpperMedianInPlace(&v), 6);
  EXPECT_EQ(RankInPlace(&v, 0), 1);
  EXPECT_EQ(RankInPlace(&v, 3), 8);
  std::vector<int> odd = {9, 3, 5};
  EXPECT_EQ(UpperMedianInPlace(&odd), 5);
}

// The rank n / 2 of a sorted copy: an oracle that shares nothing with
// either selection.
float SortedUpperMedian(std::vector<float> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

TEST(UpperMedianBySelection, TheSortedValueOnEveryKindOfSample) {
  std::mt19937 rng(7);
  std::normal_distribution<float> normal(0, 1);
  const float denormal = std::numeric_limits<float>::denorm_min();
  const float inf = std::numeric_limits<float>::infinity();
  int checked = 0;
  for (const size_t n : {1, 2, 3, 63, 64, 65, 100, 751, 4096, 11881}) {
    for (int kind = 0; kind < 7; ++kind) {
      std::vector<float> v(n);
      for (size_t i = 0; i < n; ++i) {
        const float x = normal(rng);
        switch (kind) {
          case 0:  // noise responses: |N(0, s^2)| at one scale
            v[i] = std::abs(0.01f * x);
            break;
          case 1:  // spanning many octaves
            v[i] = std::abs(x) * std::pow(10.0f, (i % 13) - 6.0f);
            break;
          case 2:  // many ties, zeros among them
            v[i] = static_cast<float>(static_cast<int>(3 * std::abs(x)));
            break;
          case 3:  // all in one of the 4096 ranges
            v[i] = 1.0f + 1e-3f * std::abs(x);
            break;
          case 4:  // signed, with denormals and infinities
            v[i] = i % 17 == 0   ? denormal * (i % 3)
                   : i % 29 == 0 ? (x > 0 ? inf : -inf)
                                 : x;
            break;
          case 5:  // one value
            v[i] = 0.25f;
            break;
          default:  // sorted descending (a bad case for pivots)
            v[i] = static_cast<float>(n - i);
            break;
        }
      }
      const float expected = SortedUpperMedian(v);
      std::vector<float> copy = v;
      EXPECT_EQ(UpperMedianBySelection(&copy), expected)
          << "n " << n << ", kind " << kind;
      ++checked;
    }
  }
  EXPECT_EQ(checked, 70);
}

TEST(UpperMedianBySelection, WithANaNAsUpperMedianInPlace) {
  std::vector<float> v(500);
  for (size_t i = 0; i < v.size(); ++i) v[i] = static_cast<float>(i % 37);
  v[123] = std::numeric_limits<float>::quiet_NaN();
  std::vector<float> a = v, b = v;
  const float expected = UpperMedianInPlace(&a);
  const float got = UpperMedianBySelection(&b);
  EXPECT_TRUE(got == expected || (std::isnan(got) && std::isnan(expected)));
  // The counts the selection keeps between calls were cleared on the way
  // out: the next call on the same values without the NaN is exact.
  v[123] = 0;
  std::vector<float> c = v;
  EXPECT_EQ(UpperMedianBySelection(&c), SortedUpperMedian(v));
}

TEST(SigmaFromMedianAbsolute, HalfNormalMedian) {
  // Phi^-1(0.75) = 0.6744897...: a median |x| of 0.67449 is one sigma, and
  // through a filter of gain 6, six times that is one sigma.
  EXPECT_NEAR(SigmaFromMedianAbsolute(0.6744897), 1.0, 1e-5);
  EXPECT_NEAR(SigmaFromMedianAbsolute(6 * 0.6744897, 6.0), 1.0, 1e-5);
}

}  // namespace
}  // namespace dpsfm
