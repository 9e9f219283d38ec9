// Timing for the benchmarks: a steady clock and the median of rounds.
#pragma once

#include <algorithm>
#include <chrono>
#include <vector>

namespace dpsfm {
namespace bench {

// Seconds on a steady clock.
inline double Now() {
  return std::chrono::duration<double>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

// The median of `rounds` values of `measure()` (each round's own timing).
template <typename Measure>
double MedianOf(int rounds, Measure measure) {
  std::vector<double> values;
  for (int r = 0; r < rounds; ++r) values.push_back(measure());
  std::nth_element(values.begin(), values.begin() + rounds / 2, values.end());
  return values[rounds / 2];
}

}  // namespace bench
}  // namespace dpsfm
