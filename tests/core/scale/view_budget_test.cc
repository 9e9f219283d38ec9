#include "dpsfm/core/scale/view_budget.h"

#include <set>

#include <gtest/gtest.h>

namespace dpsfm {
namespace {

ViewPlacement At(double x, double y, int camera = 1, double f_number = 4) {
  ViewPlacement p;
  p.centre = Eigen::Vector3d(x, y, 0);
  p.camera_id = camera;
  p.f_number = f_number;
  return p;
}

}  // namespace

// Views on a line, listed in order: the spread order visits the far end
// second and the middle third, not the neighbours of the first view.
TEST(SpreadViewOrder, FarthestFirst) {
  std::vector<ViewPlacement> views;
  for (int i = 0; i < 9; ++i) views.push_back(At(i, 0));
  const std::vector<int> order = SpreadViewOrder(views);
  ASSERT_EQ(order.size(), 9u);
  EXPECT_EQ(order[0], 0);
  EXPECT_EQ(order[1], 8);
  EXPECT_EQ(order[2], 4);
  EXPECT_EQ(std::set<int>(order.begin(), order.end()).size(), 9u);
}

// Repeated viewpoints (a project shot twice over the same path) are
// visited only after every distinct one; a second camera or aperture at
// the same place counts as new.
TEST(SpreadViewOrder, RepeatsLastOtherCamerasEarly) {
  std::vector<ViewPlacement> views;
  for (int repeat = 0; repeat < 3; ++repeat) {
    for (int i = 0; i < 4; ++i) views.push_back(At(i, 0));
  }
  views.push_back(At(0, 0, 2));      // another camera at view 0's place
  views.push_back(At(0, 0, 1, 16));  // another aperture there
  const std::vector<int> order = SpreadViewOrder(views);
  std::set<int> first(order.begin(), order.begin() + 6);
  for (const int i : {0, 1, 2, 3, 12, 13}) {
    EXPECT_EQ(first.count(i), 1u) << i;
  }
  EXPECT_TRUE(SpreadViewOrder({}).empty());
}

// The stopping rule: checkpoints from min_views every check_every views;
// it stops only after two successful checkpoints that agree and whose
// interval no longer shrinks; the cap and all_views bound the plan.
TEST(ViewBudget, StopsWhenTheScaleSettles) {
  ViewBudgetOptions options;
  options.min_views = 14;
  options.check_every = 7;
  options.max_views = 60;
  ViewBudget budget(options, 300);
  EXPECT_EQ(budget.Planned(), 60);
  EXPECT_FALSE(budget.IsCheckpoint(13));
  EXPECT_TRUE(budget.IsCheckpoint(14));
  EXPECT_FALSE(budget.IsCheckpoint(15));
  EXPECT_TRUE(budget.IsCheckpoint(21));
  EXPECT_FALSE(budget.IsCheckpoint(60));  // the last view: the final estimate
  std::string why;
  EXPECT_FALSE(budget.Record({14, false, 0, 0, 0}, &why));
  EXPECT_FALSE(budget.Record({21, true, 1.00, 0.90, 1.10}, &why));
  // 2 % apart: not settled.
  EXPECT_FALSE(budget.Record({28, true, 1.02, 0.93, 1.11}, &why));
  // 0.2 % apart but the interval shrank from 0.18 to 0.12: not settled.
  EXPECT_FALSE(budget.Record({35, true, 1.022, 0.96, 1.08}, &why));
  // 0.1 % apart, interval 0.118 against 0.12: settled.
  EXPECT_TRUE(budget.Record({42, true, 1.023, 0.964, 1.082}, &why));
  EXPECT_NE(why.find("settled after 42 views"), std::string::npos) << why;

  options.all_views = true;
  ViewBudget all(options, 300);
  EXPECT_EQ(all.Planned(), 300);
  EXPECT_FALSE(all.IsCheckpoint(14));
  options.all_views = false;
  options.max_views = 0;
  EXPECT_EQ(ViewBudget(options, 300).Planned(), 300);
  options.max_views = 10;  // below min_views
  EXPECT_FALSE(options.Check());
  EXPECT_THROW(ViewBudget(options, 300), std::invalid_argument);
  options.max_views = 60;
  options.settled_change = 0;
  EXPECT_FALSE(options.Check());
}

}  // namespace dpsfm
