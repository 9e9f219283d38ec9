#include "dpsfm/core/util/curve_math.h"

#include "dpsfm/core/util/check.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace dpsfm {

double CurveMinimum(const std::vector<double>& xs,
                    const std::vector<double>& ys,
                    size_t* index) {
  const size_t k = std::min_element(ys.begin(), ys.end()) - ys.begin();
  if (index != nullptr) *index = k;
  if (k == 0 || k + 1 >= xs.size()) return xs[k];
  const double x0 = xs[k - 1], x1 = xs[k], x2 = xs[k + 1];
  const double y0 = ys[k - 1], y1 = ys[k], y2 = ys[k + 1];
  const double denom = (x0 - x1) * (x0 - x2) * (x1 - x2);
  if (denom == 0) return x1;
  const double a = (x2 * (y1 - y0) + x1 * (y0 - y2) + x0 * (y2 - y1)) / denom;
  const double b =
      (x2 * x2 * (y0 - y1) + x1 * x1 * (y2 - y0) + x0 * x0 * (y1 - y2)) / denom;
  if (!(a > 0)) return x1;
  return std::max(x0, std::min(x2, -b / (2 * a)));
}

std::vector<double> GeometricNodes(double lo, double hi, double ratio) {
  DPSFM_CHECK(lo > 0 && hi > lo && ratio > 1 && std::isfinite(hi))
      << "GeometricNodes needs 0 < lo < hi and ratio > 1";
  std::vector<double> nodes;
  for (int k = 0;; ++k) {
    const double x = lo * std::pow(ratio, k);
    // A node within 1e-6 of hi is hi.
    if (x >= hi * (1 - 1e-6)) break;
    nodes.push_back(x);
  }
  nodes.push_back(hi);
  return nodes;
}

}  // namespace dpsfm
