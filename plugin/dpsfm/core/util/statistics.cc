#include "dpsfm/core/util/statistics.h"

#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
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

namespace {

// A float's bits mapped so that unsigned order is the values' order
// (negative values reversed below the positive ones).
inline uint32_t OrderedBits(float value) {
  uint32_t bits;
  std::memcpy(&bits, &value, sizeof(bits));
  return bits ^ ((bits & 0x80000000u) != 0 ? 0xffffffffu : 0x80000000u);
}

}  // namespace

float UpperMedianBySelection(std::vector<float>* values) {
  const size_t n = values->size();
  // Below ~128 values std::nth_element is as fast (the counts, 16 KB, are
  // cleared every call): 0.8 us against 1.5 at 64 values, even at 128.
  constexpr size_t kSmall = 128;
  if (n < kSmall) return UpperMedianInPlace(values);
  constexpr int kShift = 20;  // 12 leading bits: 4096 ranges
  std::array<uint32_t, size_t{1} << (32 - kShift)> counts{};
  float* v = values->data();
  bool any_nan = false;
  for (size_t i = 0; i < n; ++i) {
    ++counts[OrderedBits(v[i]) >> kShift];
    any_nan |= std::isnan(v[i]);
  }
  if (any_nan) return UpperMedianInPlace(values);
  // The range that holds rank n / 2, and how many values lie below it.
  const size_t k = n / 2;
  size_t range = 0, below = 0;
  while (below + counts[range] <= k) below += counts[range++];
  // Its values to the front (in place: each is written at or before where
  // it was read), then the rank within them.
  size_t m = 0;
  for (size_t i = 0; i < n; ++i) {
    if ((OrderedBits(v[i]) >> kShift) == range) v[m++] = v[i];
  }
  std::nth_element(v, v + (k - below), v + m);
  return v[k - below];
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
