// The view budget through the command (docs/user-guide.md, "Large
// projects"): the order, the stopping rule, the cap and all_views, on the
// generated 8-view DSLR scene with a small budget.
#include <set>
#include <string>

#include <gtest/gtest.h>

#include "tests/e2e/e2e_helpers.h"

namespace dpsfm {
namespace test {
namespace {

struct BudgetRun {
  CommandResult command;
  nlohmann::json report;
};

BudgetRun RunWithBudget(const SceneCopy& scene,
                        const std::string& name,
                        const std::vector<std::string>& budget) {
  const std::string report = scene.temp() / (name + ".json");
  BudgetRun run;
  run.command = RunEstimator(
      With(With(DenseArgs(scene), {"--dry_run", "1", "--report_path", report}),
           budget));
  EXPECT_EQ(run.command.exit_code, 0) << run.command.err;
  if (run.command.exit_code == 0) run.report = ReadJson(report);
  return run;
}

}  // namespace

TEST(ViewBudgetCommand, StopsCapsOrVisitsAll) {
  SceneCopy scene("dslr");
  const double truth =
      ReadJson(scene / "ground_truth.json").at("scale").get<double>();

  // Every view: no checkpoints, nothing skipped; read one by one here.
  const BudgetRun all = RunWithBudget(scene,
                                      "all",
                                      {"--DPScaleEstimator.all_views",
                                       "1",
                                       "--DPScaleEstimator.prefetch_views",
                                       "0"});
  ASSERT_TRUE(all.report.contains("view_budget"));
  const nlohmann::json& a = all.report.at("view_budget");
  EXPECT_EQ(a.at("views_visited").get<int>(), 8);
  EXPECT_TRUE(a.at("skipped").empty());
  EXPECT_TRUE(a.at("checkpoints").empty());
  EXPECT_EQ(a.at("stop_reason").get<std::string>(), "");
  const double all_scale = all.report.at("scale").get<double>();
  // Reading three views ahead on worker threads changes nothing but when
  // the reads happen.
  const BudgetRun ahead = RunWithBudget(scene,
                                        "ahead",
                                        {"--DPScaleEstimator.all_views",
                                         "1",
                                         "--DPScaleEstimator.prefetch_views",
                                         "3"});
  EXPECT_DOUBLE_EQ(ahead.report.at("scale").get<double>(), all_scale);
  EXPECT_EQ(ahead.report.at("view_budget").at("visited"), a.at("visited"));
  const nlohmann::json& timings = ahead.report.at("timings");
  EXPECT_GT(timings.at("read").get<double>(), 0);
  EXPECT_LE(timings.at("read_wait").get<double>(),
            timings.at("read").get<double>() + 0.05);

  // The stopping rule from 4 views, every 2: it may stop at 6 views (the
  // last checkpoint before the final view) only if the scale settled, and
  // then the answer is the last checkpoint's.
  const BudgetRun rule = RunWithBudget(scene,
                                       "rule",
                                       {"--DPScaleEstimator.min_views",
                                        "4",
                                        "--DPScaleEstimator.check_every",
                                        "2"});
  const nlohmann::json& r = rule.report.at("view_budget");
  const int visited = r.at("views_visited").get<int>();
  EXPECT_EQ(visited + static_cast<int>(r.at("skipped").size()), 8);
  ASSERT_GE(r.at("checkpoints").size(), 1u);
  EXPECT_EQ(r.at("checkpoints")[0].at("views").get<int>(), 4);
  // Each checkpoint's estimate is timed, within the run's total.
  double checkpoint_seconds = 0;
  for (const auto& c : r.at("checkpoints")) {
    EXPECT_GT(c.at("seconds").get<double>(), 0) << c.dump();
    checkpoint_seconds += c.at("seconds").get<double>();
  }
  EXPECT_LT(checkpoint_seconds,
            rule.report.at("timings").at("total").get<double>());
  // Visited in the spread order: every image once, the first one first.
  std::set<std::string> names;
  for (const auto& n : r.at("visited")) names.insert(n.get<std::string>());
  for (const auto& n : r.at("skipped")) names.insert(n.get<std::string>());
  EXPECT_EQ(names.size(), 8u);
  EXPECT_EQ(rule.report.at("views").size(), static_cast<size_t>(visited));
  if (visited < 8) {
    EXPECT_NE(r.at("stop_reason").get<std::string>().find("settled"),
              std::string::npos)
        << r.dump(2);
    EXPECT_DOUBLE_EQ(rule.report.at("scale").get<double>(),
                     r.at("checkpoints").back().at("scale").get<double>());
  }
  const double scale = rule.report.at("scale").get<double>();
  std::printf("all views %.5f, rule (%d views) %.5f, truth %.5f\n",
              all_scale,
              visited,
              scale,
              truth);
  EXPECT_LE(rule.report.at("scale_ci_low").get<double>(), truth);
  EXPECT_GE(rule.report.at("scale_ci_high").get<double>(), truth);
  EXPECT_NEAR(scale / all_scale, 1.0, 0.02);

  // A cap of 5 views: 5 visited, the budget named as the reason.
  const BudgetRun capped = RunWithBudget(scene,
                                         "capped",
                                         {"--DPScaleEstimator.min_views",
                                          "5",
                                          "--DPScaleEstimator.max_views",
                                          "5"});
  const nlohmann::json& c = capped.report.at("view_budget");
  EXPECT_EQ(c.at("views_visited").get<int>(), 5);
  EXPECT_EQ(c.at("skipped").size(), 3u);
  EXPECT_NE(c.at("stop_reason").get<std::string>().find("max_views 5"),
            std::string::npos)
      << c.dump(2);

  // A cap below the minimum is refused in one line.
  const CommandResult bad = RunEstimator(With(DenseArgs(scene),
                                              {"--dry_run",
                                               "1",
                                               "--DPScaleEstimator.max_views",
                                               "3",
                                               "--DPScaleEstimator.min_views",
                                               "4"}));
  EXPECT_EQ(bad.exit_code, 1);
  EXPECT_NE(bad.err.find("ERROR: dp_scale_estimator: invalid "
                         "DPScaleEstimator view budget"),
            std::string::npos)
      << bad.err;
  const CommandResult bad_prefetch = RunEstimator(
      With(DenseArgs(scene),
           {"--dry_run", "1", "--DPScaleEstimator.prefetch_views", "-1"}));
  EXPECT_EQ(bad_prefetch.exit_code, 1);
  EXPECT_NE(bad_prefetch.err.find("prefetch_views must be in [0, 8], got -1"),
            std::string::npos)
      << bad_prefetch.err;
}

}  // namespace test
}  // namespace dpsfm
