#include "dpsfm/core/util/curve_math.h"

#include <cmath>

#include <gtest/gtest.h>

namespace dpsfm {

// Extending the range keeps the nodes inside the old one where they were.
TEST(GeometricNodes, SpacingKeptWhenTheRangeGrows) {
  const double q = std::pow(0.414 / 0.03, 1.0 / 16);
  const std::vector<double> old_nodes = GeometricNodes(0.03, 0.414, q);
  ASSERT_EQ(old_nodes.size(), 17u);
  const std::vector<double> nodes = GeometricNodes(0.03, 0.47, q);
  ASSERT_EQ(nodes.size(), 18u);
  for (size_t k = 0; k < old_nodes.size(); ++k) {
    EXPECT_NEAR(nodes[k], old_nodes[k], 1e-9 * old_nodes[k]) << k;
  }
  EXPECT_DOUBLE_EQ(nodes.back(), 0.47);
  EXPECT_THROW(GeometricNodes(0.1, 0.05, 1.2), std::invalid_argument);
  EXPECT_THROW(GeometricNodes(0.1, 0.5, 1.0), std::invalid_argument);
}

TEST(CurveMinimum, VertexOfTheParabola) {
  // y = (x - 0.3)^2 sampled at 0, 0.25, 0.5, 1: the vertex is exact.
  const std::vector<double> xs = {0, 0.25, 0.5, 1};
  std::vector<double> ys;
  for (const double x : xs) ys.push_back((x - 0.3) * (x - 0.3));
  size_t index = 9;
  EXPECT_NEAR(CurveMinimum(xs, ys, &index), 0.3, 1e-12);
  EXPECT_EQ(index, 1u);
}

}  // namespace dpsfm
