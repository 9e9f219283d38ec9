// FieldCount, TieFields and SameFields: what the caches compare their
// options with, tested against structs whose fields are written out here.
#include <cmath>
#include <limits>
#include <string>

#include <gtest/gtest.h>

#include "dpsfm/core/blur/blur_estimation.h"
#include "dpsfm/core/util/fields.h"
#include "tests/changed_fields.h"

namespace dpsfm {
namespace {

struct Three {
  double x = 1.5;
  bool flag = true;
  int count = 7;
};

struct WithDefaultsAndMethods {
  double a = 0, b = 0;
  std::string name = "n";
  int Sum() const { return static_cast<int>(a + b); }
};

struct Sixteen {
  int f0 = 0, f1 = 1, f2 = 2, f3 = 3, f4 = 4, f5 = 5, f6 = 6, f7 = 7;
  int f8 = 8, f9 = 9, f10 = 10, f11 = 11, f12 = 12, f13 = 13, f14 = 14,
      f15 = 15;
};

TEST(FieldCount, CountsDataMembersOnly) {
  static_assert(FieldCount<Three>() == 3, "three fields");
  static_assert(FieldCount<WithDefaultsAndMethods>() == 3, "three fields");
  static_assert(FieldCount<Sixteen>() == 16, "sixteen fields");
  EXPECT_EQ(FieldCount<Three>(), 3u);
}

TEST(TieFields, InDeclarationOrderAsReferences) {
  Three s;
  auto tied = TieFields(s);
  EXPECT_EQ(std::get<0>(tied), 1.5);
  EXPECT_TRUE(std::get<1>(tied));
  EXPECT_EQ(std::get<2>(tied), 7);
  std::get<2>(tied) = 9;
  EXPECT_EQ(s.count, 9);
  const Sixteen sixteen;
  EXPECT_EQ(std::get<15>(TieFields(sixteen)), 15);
  EXPECT_EQ(std::get<8>(TieFields(sixteen)), 8);
}

TEST(SameFields, AnyOneFieldDiffers) {
  const WithDefaultsAndMethods s;
  EXPECT_TRUE(SameFields(s, WithDefaultsAndMethods()));
  WithDefaultsAndMethods other = s;
  other.name = "m";
  EXPECT_FALSE(SameFields(s, other));
  other = s;
  other.b = -0.0;  // == compares values: -0 is 0
  EXPECT_TRUE(SameFields(s, other));
  other.b = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(SameFields(other, other));  // a NaN field: never the same
  int changed = 0;
  test::ForEachFieldChanged(Sixteen(), [&](std::size_t i, const Sixteen& c) {
    EXPECT_FALSE(SameFields(c, Sixteen())) << "field " << i;
    ++changed;
  });
  EXPECT_EQ(changed, 16);
}

// The blur search's options, the key of two caches: each field changed
// alone makes them differ, and the count is the struct's, whatever it holds.
TEST(SameFields, EachBlurSearchOptionCounts) {
  const BlurEstimationOptions defaults;
  EXPECT_TRUE(SameFields(defaults, BlurEstimationOptions()));
  std::size_t changed = 0;
  test::ForEachFieldChanged(
      defaults, [&](std::size_t i, const BlurEstimationOptions& c) {
        EXPECT_FALSE(SameFields(c, defaults)) << "field " << i;
        EXPECT_TRUE(c.Check()) << "field " << i << " changed is invalid";
        ++changed;
      });
  EXPECT_EQ(changed, FieldCount<BlurEstimationOptions>());
  EXPECT_GE(changed, 11u);
}

}  // namespace
}  // namespace dpsfm
