// Which views a large project needs, and when to stop adding them.
//
// The method's answer rests on N_v selected views (7) and the best patches
// of each, so a project of hundreds or thousands of views needs only as
// many as it takes for the scale and its interval to settle. Two parts:
// - an order (SpreadViewOrder): views visited spread over the
//   reconstruction, each next view the one farthest from all visited ones
//   in viewpoint (camera centre and viewing direction), aperture and
//   camera, so an early stop still samples the whole project;
// - a stopping rule (ViewBudget): after min_views views, the scale is
//   estimated from the views so far every check_every views; the run stops
//   when two consecutive checkpoints both give a scale, they agree to
//   settled_change, and the interval stopped shrinking (the later one is
//   wider than settled_shrink times the earlier one). max_views caps the
//   views visited (memory: each visited view keeps its best patches'
//   crops), all_views visits every view.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

namespace dpsfm {

struct ViewPlacement {
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  // Unit viewing direction (the camera's +z in the world).
  Eigen::Vector3d direction = Eigen::Vector3d::UnitZ();
  double f_number = 0;  // 0 = unknown
  int camera_id = 0;
};

// Visiting order over all views: the first view first, then greedy
// farthest-point sampling. The distance between two views adds the camera
// centres' distance over the project's spread (RMS distance of the centres
// to their mean), the angle between the viewing directions over 90
// degrees, the f-numbers' log2 ratio, and 1 for different cameras.
std::vector<int> SpreadViewOrder(const std::vector<ViewPlacement>& views);

struct ViewBudgetOptions {
  int min_views = 14;   // 2 N_v
  int check_every = 7;  // N_v
  double settled_change = 0.005;
  double settled_shrink = 0.9;
  int max_views = 60;
  bool all_views = false;
  bool Check(std::string* failure = nullptr) const;
};

struct Checkpoint {
  int views = 0;
  bool success = false;
  double scale = 0, ci_low = 0, ci_high = 0;
  double seconds = 0;  // the estimate's time (the caller's measurement)
};

class ViewBudget {
 public:
  ViewBudget(const ViewBudgetOptions& options, int num_views);

  // How many views the run will visit at most.
  int Planned() const { return planned_; }
  // Whether the scale is to be estimated after `visited` views.
  bool IsCheckpoint(int visited) const;
  // Records a checkpoint; true when the rule says stop (*why says why).
  bool Record(const Checkpoint& checkpoint, std::string* why);
  const std::vector<Checkpoint>& Checkpoints() const { return checkpoints_; }

 private:
  ViewBudgetOptions options_;
  int num_views_;
  int planned_;
  std::vector<Checkpoint> checkpoints_;
};

}  // namespace dpsfm
