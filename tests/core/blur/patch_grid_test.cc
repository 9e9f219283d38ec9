// The patch grid and the per-patch depth statistics (core/blur/patch_grid.h)
// against positions, counts and statistics computed by hand.
#include "dpsfm/core/blur/patch_grid.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include <gtest/gtest.h>

namespace dpsfm {
namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
constexpr float kInf = std::numeric_limits<float>::infinity();

// A 40 x 30 frame, patches of 10 every 8 px with a border of 3: interiors
// start at 3 and fit while start + 10 + 3 <= size, so x in {3, 11, 19, 27}
// (35 + 13 > 40) and y in {3, 11} (19 + 13 > 30): 4 x 2 = 8, row by row.
// 40 x 30, patches of 10 every 8 px with a border of 3: the lattice is
// centred (a patch at (40 - 10) / 2 = 15 across, (30 - 10) / 2 = 10 down),
// and keeps the positions whose crop fits: x = 7, 15, 23 (31 + 10 + 3 > 40;
// -1 < 3), y = 10 (18 + 10 + 3 > 30, 2 < 3).
TEST(MakePatchGrid, PositionsAndCountByHand) {
  const std::vector<PatchCandidate> grid =
      MakePatchGrid(cv::Size(40, 30), 10, 8, 3);
  ASSERT_EQ(grid.size(), 3u);
  const int xs[] = {7, 15, 23};
  for (int col = 0; col < 3; ++col) {
    const PatchCandidate& c = grid[col];
    EXPECT_EQ(c.interior, cv::Rect(xs[col], 10, 10, 10)) << "col " << col;
    EXPECT_EQ(c.reject, "");
    EXPECT_FALSE(c.depth.ok);
  }
  EXPECT_EQ(PatchCrop(grid.back().interior, 3), cv::Rect(20, 7, 16, 16));
  // 16 x 16 holds exactly one patch with its border; 15 x 16 none.
  EXPECT_EQ(MakePatchGrid(cv::Size(16, 16), 10, 8, 3).size(), 1u);
  EXPECT_EQ(MakePatchGrid(cv::Size(15, 16), 10, 8, 3).size(), 0u);
}

// A wider border (a larger search bound) drops positions at the edges and
// moves none: every patch of the wider grid is one of the narrower grid's.
TEST(MakePatchGrid, AWiderBorderMovesNoPatch) {
  const cv::Size size(768, 512);
  const std::vector<PatchCandidate> narrow = MakePatchGrid(size, 31, 17, 9);
  const std::vector<PatchCandidate> wide = MakePatchGrid(size, 31, 17, 17);
  ASSERT_LT(wide.size(), narrow.size());
  ASSERT_GT(wide.size(), 0.8 * narrow.size());
  for (const PatchCandidate& w : wide) {
    EXPECT_TRUE(std::any_of(
        narrow.begin(),
        narrow.end(),
        [&](const PatchCandidate& n) { return n.interior == w.interior; }))
        << w.interior;
  }
}

// Twenty values 1..20: the upper median is the value of rank 20 / 2 = 10
// (11), p10 of rank 20 / 10 = 2 (3), p90 of rank 9 * 20 / 10 = 18 (19):
// spread (19 - 3) / 11 = 16 / 11; mean 10.5, variance (20^2 - 1) / 12 =
// 33.25, relative to 11^2: 33.25 / 121.
TEST(DepthStatsOf, MedianSpreadAndVarianceByHand) {
  std::vector<float> even = {7, 13, 3,  20, 10, 1,  16, 6,  9,  18,
                             2, 8,  15, 5,  4,  19, 12, 11, 17, 14};
  const DepthStats a = DepthStatsOf(&even);
  EXPECT_TRUE(a.ok);
  EXPECT_DOUBLE_EQ(a.median, 11);
  EXPECT_DOUBLE_EQ(a.relative_spread, 16.0 / 11.0);
  EXPECT_DOUBLE_EQ(a.relative_variance, 33.25 / 121.0);
  // Five values {3, 4, 4, 4, 5}: median 4, p10 rank 0 (3), p90 rank 4 (5),
  // spread 2 / 4; variance (1 + 0 + 0 + 0 + 1) / 5 = 0.4, / 16.
  std::vector<float> odd = {4, 5, 4, 3, 4};
  const DepthStats b = DepthStatsOf(&odd);
  EXPECT_TRUE(b.ok);
  EXPECT_DOUBLE_EQ(b.median, 4);
  EXPECT_DOUBLE_EQ(b.relative_spread, 0.5);
  EXPECT_NEAR(b.relative_variance, 0.4 / 16.0, 1e-15);
  // Nothing, or a median of 0: no statistics.
  std::vector<float> none;
  EXPECT_FALSE(DepthStatsOf(&none).ok);
  std::vector<float> zeros = {0, 0, 0};
  EXPECT_FALSE(DepthStatsOf(&zeros).ok);
}

// Against a full sort, for every size from 1 to 60 with repeated values:
// the median and the ranks n / 10 and 9 n / 10 (the spread).
TEST(DepthStatsOf, PercentilesAsASortGivesThem) {
  std::mt19937 rng(3);
  std::uniform_int_distribution<int> value(1, 9);
  for (size_t n = 1; n <= 60; ++n) {
    std::vector<float> v(n);
    for (float& x : v) x = static_cast<float>(value(rng));
    std::vector<float> sorted = v;
    std::sort(sorted.begin(), sorted.end());
    const DepthStats s = DepthStatsOf(&v);
    const double median = sorted[n / 2];
    EXPECT_EQ(s.median, median) << n;
    EXPECT_DOUBLE_EQ(
        s.relative_spread,
        (sorted[std::min(n - 1, 9 * n / 10)] - sorted[n / 10]) / median)
        << n;
  }
}

// A dense map at a quarter of an 80 x 60 frame (20 x 15) under a working
// frame of half the frame (sx = sy = 0.5). A working interior of 10 px at
// (x, 4) covers frame edges [2x, 2x + 20) x [8, 28); depth pixel i has its
// centre at frame (i + 0.5) * 4 = 4 i + 2, inside for i = x / 2 .. x / 2 + 4,
// and rows 2..6: 25 depth pixels per patch.
TEST(MeasurePatchDepths, DenseCoverageAndEdgesByHand) {
  cv::Mat depth(15, 20, CV_32FC1, cv::Scalar(8.0));
  // A: columns 5..9, one depth (4).
  depth(cv::Rect(5, 2, 5, 5)).setTo(4.0);
  // B: columns 0..4, 13 of 25 valid (2); 12 invalid of every kind.
  // C: columns 10..14, 12 of 25 valid (2).
  depth(cv::Rect(0, 2, 5, 5)).setTo(2.0);
  depth(cv::Rect(10, 2, 5, 5)).setTo(2.0);
  const float invalid[] = {kNaN, 0.0f, -1.0f, kInf};
  for (int k = 0; k < 13; ++k) {
    if (k < 12) depth.at<float>(2 + k / 5, k % 5) = invalid[k % 4];
    depth.at<float>(2 + k / 5, 10 + k % 5) = invalid[k % 4];
  }
  // D: columns 15..19, two columns at 3 and three at 3.6: sorted, rank 12
  // (median) is 3.6, rank 2 (p10) 3, rank 22 (p90) 3.6: spread 0.6 / 3.6.
  depth(cv::Rect(15, 2, 2, 5)).setTo(3.0);
  depth(cv::Rect(17, 2, 3, 5)).setTo(3.6);

  std::vector<PatchCandidate> candidates(4);
  const int xs[] = {10, 0, 20, 30};  // A, B, C, D
  for (int k = 0; k < 4; ++k) {
    candidates[k].interior = cv::Rect(xs[k], 4, 10, 10);
  }
  MeasurePatchDepths(
      depth, {}, cv::Size(80, 60), 0.5, 0.5, PatchDepthOptions(), &candidates);
  // A: only its own 25 pixels (one more row or column would bring in 8s and
  // a spread of 1).
  EXPECT_EQ(candidates[0].reject, "");
  EXPECT_TRUE(candidates[0].depth.ok);
  EXPECT_DOUBLE_EQ(candidates[0].depth.median, 4);
  EXPECT_DOUBLE_EQ(candidates[0].depth.relative_spread, 0);
  // B: 13 >= 0.5 x 25 valid.
  EXPECT_EQ(candidates[1].reject, "");
  EXPECT_DOUBLE_EQ(candidates[1].depth.median, 2);
  // C: 12 < 12.5.
  EXPECT_EQ(candidates[2].reject, "without depth");
  // D: 0.1667 > 0.1.
  EXPECT_EQ(candidates[3].reject, "across a depth edge");
  EXPECT_NEAR(candidates[3].depth.relative_spread, 0.6 / 3.6, 1e-6);
  EXPECT_NEAR(candidates[3].depth.median, 3.6, 1e-6);
}

// Sparse points in frame pixels (centres at integers) under sx = sy = 0.5:
// the working interior (10, 4, 10, 10) covers frame edges [20, 40) x
// [8, 28), i.e. points with x + 0.5 in [20, 40): x = 19.5 is in, 39.5 out.
TEST(MeasurePatchDepths, SparsePointsByHand) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const std::vector<DepthPoint> points = {
      {19.5, 10, 2.0},   // on the left edge: in
      {30, 27.4, 2.0},   // 27.9 < 28: in
      {25, 15, 2.1},     // in
      {39.5, 15, 50.0},  // on the right edge: out
      {25, 27.5, 50.0},  // on the bottom edge: out
      {25, 15, nan},     // in, but no depth
      {26, 15, 0.0},     // in, but not positive
  };
  std::vector<PatchCandidate> candidates(1);
  candidates[0].interior = cv::Rect(10, 4, 10, 10);
  PatchDepthOptions options;  // min_points 3
  std::vector<PatchCandidate> kept = candidates;
  MeasurePatchDepths(
      cv::Mat(), points, cv::Size(80, 60), 0.5, 0.5, options, &kept);
  // {2, 2, 2.1}: median (rank 1) 2, p10 rank 0 (2), p90 rank 2 (2.1):
  // spread 0.05.
  EXPECT_EQ(kept[0].reject, "");
  EXPECT_DOUBLE_EQ(kept[0].depth.median, 2);
  EXPECT_NEAR(kept[0].depth.relative_spread, 0.05, 1e-6);
  // Four needed: three is too few.
  options.min_points = 4;
  std::vector<PatchCandidate> dropped = candidates;
  MeasurePatchDepths(
      cv::Mat(), points, cv::Size(80, 60), 0.5, 0.5, options, &dropped);
  EXPECT_EQ(dropped[0].reject, "without depth");
}

// Candidates measured in parallel come out as one thread measures them: a
// depth map of random planes with holes, every kind of outcome present.
TEST(MeasurePatchDepths, AnyNumberOfThreadsGivesTheSameStatistics) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> unit(0, 1);
  cv::Mat map(240, 320, CV_32FC1);
  for (int y = 0; y < map.rows; ++y) {
    for (int x = 0; x < map.cols; ++x) {
      const float plane = (x / 37 + y / 29) % 3 == 0 ? 1.5f : 2.5f;
      map.at<float>(y, x) = unit(rng) < 0.2f ? kNaN : plane + 0.01f * x;
    }
  }
  map(cv::Rect(200, 100, 90, 90)).setTo(0);
  const std::vector<PatchCandidate> grid =
      MakePatchGrid(cv::Size(160, 120), 12, 5, 2);
  PatchDepthOptions options;
  std::vector<PatchCandidate> one = grid, two = grid;
  MeasurePatchDepths(map, {}, map.size(), 0.5, 0.5, options, &one);
  options.num_threads = 2;
  MeasurePatchDepths(map, {}, map.size(), 0.5, 0.5, options, &two);
  ASSERT_EQ(one.size(), two.size());
  int kept = 0, without = 0, across = 0;
  for (size_t k = 0; k < one.size(); ++k) {
    EXPECT_EQ(one[k].reject, two[k].reject) << k;
    EXPECT_EQ(one[k].depth.median, two[k].depth.median) << k;
    EXPECT_EQ(one[k].depth.relative_spread, two[k].depth.relative_spread) << k;
    EXPECT_EQ(one[k].depth.relative_variance, two[k].depth.relative_variance)
        << k;
    kept += one[k].reject.empty();
    without += one[k].reject == "without depth";
    across += one[k].reject == "across a depth edge";
  }
  EXPECT_GT(kept, 0);
  EXPECT_GT(without, 0);
  EXPECT_GT(across, 0);
}

}  // namespace
}  // namespace dpsfm
