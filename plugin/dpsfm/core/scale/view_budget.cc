#include "dpsfm/core/scale/view_budget.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include "dpsfm/core/util/check.h"

namespace dpsfm {

std::vector<int> SpreadViewOrder(const std::vector<ViewPlacement>& views) {
  const int n = static_cast<int>(views.size());
  std::vector<int> order;
  if (n == 0) return order;
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const ViewPlacement& v : views) mean += v.centre;
  mean /= n;
  double spread = 0;
  for (const ViewPlacement& v : views)
    spread += (v.centre - mean).squaredNorm();
  spread = std::sqrt(spread / n);
  if (!(spread > 0)) spread = 1;
  auto distance = [&](const ViewPlacement& a, const ViewPlacement& b) {
    double d = (a.centre - b.centre).norm() / spread;
    const double cosine = std::max(
        -1.0,
        std::min(1.0, a.direction.normalized().dot(b.direction.normalized())));
    d += std::acos(cosine) / (0.5 * M_PI);
    if (a.f_number > 0 && b.f_number > 0) {
      d += std::abs(std::log2(a.f_number / b.f_number));
    }
    if (a.camera_id != b.camera_id) d += 1;
    return d;
  };
  // nearest[i]: distance from view i to the nearest visited view.
  std::vector<double> nearest(n, std::numeric_limits<double>::infinity());
  std::vector<bool> visited(n, false);
  int next = 0;
  for (int k = 0; k < n; ++k) {
    order.push_back(next);
    visited[next] = true;
    int best = -1;
    for (int i = 0; i < n; ++i) {
      if (visited[i]) continue;
      nearest[i] = std::min(nearest[i], distance(views[i], views[next]));
      // Ties (repeated viewpoints) go to the earlier view.
      if (best < 0 || nearest[i] > nearest[best]) best = i;
    }
    next = best;
  }
  return order;
}

bool ViewBudgetOptions::Check(std::string* failure) const {
  DPSFM_CHECK_OPTION_GE(min_views, 1);
  DPSFM_CHECK_OPTION_GE(check_every, 1);
  DPSFM_CHECK_OPTION_VALUE(settled_change > 0 && settled_change < 1,
                           settled_change);
  DPSFM_CHECK_OPTION_VALUE(settled_shrink > 0 && settled_shrink <= 1,
                           settled_shrink);
  // 0 is no cap.
  DPSFM_CHECK_OPTION_VALUE(max_views == 0 || max_views >= min_views, max_views);
  return true;
}

ViewBudget::ViewBudget(const ViewBudgetOptions& options, int num_views)
    : options_(options), num_views_(num_views) {
  DPSFM_CHECK_OPTIONS(options, "ViewBudgetOptions");
  planned_ = options.all_views || options.max_views == 0
                 ? num_views
                 : std::min(num_views, options.max_views);
}

bool ViewBudget::IsCheckpoint(int visited) const {
  if (options_.all_views || visited >= planned_) return false;
  return visited >= options_.min_views &&
         (visited - options_.min_views) % options_.check_every == 0;
}

bool ViewBudget::Record(const Checkpoint& checkpoint, std::string* why) {
  checkpoints_.push_back(checkpoint);
  if (checkpoints_.size() < 2) return false;
  const Checkpoint& a = checkpoints_[checkpoints_.size() - 2];
  const Checkpoint& b = checkpoints_.back();
  if (!a.success || !b.success) return false;
  const double change = std::abs(b.scale / a.scale - 1);
  const double width_a = a.ci_high - a.ci_low, width_b = b.ci_high - b.ci_low;
  if (change < options_.settled_change &&
      width_b >= options_.settled_shrink * width_a) {
    std::ostringstream s;
    s << "the scale settled after " << b.views << " views: " << b.scale
      << " against " << a.scale << " after " << a.views << " views ("
      << 100 * change << " % apart, under " << 100 * options_.settled_change
      << " %), interval " << width_b / width_a
      << " of the earlier width (not shrinking below "
      << options_.settled_shrink << ")";
    *why = s.str();
    return true;
  }
  return false;
}

}  // namespace dpsfm
