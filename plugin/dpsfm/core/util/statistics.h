// Sample statistics, in one place for every stage: medians, quantiles and the
// robust noise scale. Each variant is named for what it computes, because the
// stages use different ones on purpose (an interpolated percentile for
// bootstrap intervals, the upper median where a rank is enough and the sample
// is large, the nearest rank for plot ranges).
#pragma once

#include <algorithm>
#include <cstddef>
#include <vector>

namespace dpsfm {

// Median: the middle value, or the mean of the two middle values for an even
// count. NaN for no values.
double Median(std::vector<double> values);

// Median of the finite values only; NaN when there are none.
double FiniteMedian(std::vector<double> values);

// Percentile (q in 0..1) by linear interpolation between the sorted values
// (the "type 7" estimator of R and NumPy's default). NaN for no values.
double Percentile(std::vector<double> values, double q);

// The finite value of rank round(q (n - 1)) (q in 0..1): a quantile that is
// always one of the samples. NaN when there are no finite values.
double NearestRankQuantile(std::vector<double> values, double q);

// The value of rank k (0-based) in linear time; reorders *values.
// RankInPlace(v, v->size() / 2) is UpperMedianInPlace.
//
// The value of rank n / 2 (the median for an odd count, the upper of the two
// middle values for an even one), found in linear time. Reorders *values,
// which must not be empty.
template <typename T>
T RankInPlace(std::vector<T>* values, size_t k) {
  std::nth_element(values->begin(), values->begin() + k, values->end());
  return (*values)[k];
}
template <typename T>
T UpperMedianInPlace(std::vector<T>* values) {
  return RankInPlace(values, values->size() / 2);
}

// The value of rank n / 2 of floats, as UpperMedianInPlace gives it, by
// radix selection: one pass counts the values per range of their leading
// 12 bits (sign, exponent and three mantissa bits, in the values' order),
// the range that holds rank n / 2 is gathered, and the rank is selected
// within it. The value is exact, so the same as UpperMedianInPlace's; 4-7x
// faster than std::nth_element on 750-12000 values of half-normal noise
// (whose partitions mispredict about every other branch): the noise
// medians went from 10 % to 3 % of planes_gain's CPU (perf). The counts
// are kept per thread and a call clears only the ranges it used, rather
// than 16 KB of them: 3-7x faster again on 150-225 values (the screening's
// subsampled patches), and faster than std::nth_element from 32 values on.
// Consumes *values (contents unspecified afterwards), which must not be
// empty; with a NaN among them it is UpperMedianInPlace.
float UpperMedianBySelection(std::vector<float>* values);

// The noise sigma behind the median of absolute filter responses: for a
// filter of gain g (the norm of its taps) on N(0, sigma^2) noise, the
// responses are N(0, g^2 sigma^2) and median |x| = Phi^-1(3/4) g sigma.
constexpr double kHalfNormalMedian = 0.67449;
inline double SigmaFromMedianAbsolute(double median_absolute,
                                      double filter_gain = 1.0) {
  return median_absolute / (kHalfNormalMedian * filter_gain);
}

}  // namespace dpsfm
