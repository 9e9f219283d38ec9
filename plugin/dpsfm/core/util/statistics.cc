#include "dpsfm/core/util/statistics.h"

#include <cmath>
#include <limits>

namespace dpsfm {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

std::vector<double> FiniteOnly(std::vector<double> values) {
  values.erase(std::remove_if(values.begin(),
                              values.end(),
                              [](double v) { return !std::isfinite(v); }),
               values.end());
  return values;
}

}  // namespace

double Median(std::vector<double> values) {
  if (values.empty()) return kNaN;
  const size_t n = values.size();
  const double upper = UpperMedianInPlace(&values);
  if (n % 2 == 1) return upper;
  const double lower =
      *std::max_element(values.begin(), values.begin() + n / 2);
  return 0.5 * (lower + upper);
}

double FiniteMedian(std::vector<double> values) {
  return Median(FiniteOnly(std::move(values)));
}

double Percentile(std::vector<double> values, double q) {
  if (values.empty()) return kNaN;
  std::sort(values.begin(), values.end());
  const double pos = q * (values.size() - 1);
  const size_t lo = static_cast<size_t>(std::floor(pos));
  const size_t hi = std::min(lo + 1, values.size() - 1);
  return values[lo] + (pos - lo) * (values[hi] - values[lo]);
}

double NearestRankQuantile(std::vector<double> values, double q) {
  values = FiniteOnly(std::move(values));
  if (values.empty()) return kNaN;
  const size_t k =
      std::min(values.size() - 1,
               static_cast<size_t>(std::floor(q * (values.size() - 1) + 0.5)));
  std::nth_element(values.begin(), values.begin() + k, values.end());
  return values[k];
}

}  // namespace dpsfm
