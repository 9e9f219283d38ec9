// Loops over floats that the compiler vectorises, and the tools they share.
//
// DPSFM_VECTOR_CLONES compiles a function twice, for AVX2 and for the
// x86-64 baseline (SSE2), the loader picking one for the machine (GNU
// ifunc): four floats or doubles at a time where the baseline does two.
// Neither clone brings FMA to contract operations into, so both compute the
// same IEEE operations in the same order: the bits do not depend on the
// clone. Other compilers and machines get one plain version.
//
// Sums in double over many floats are kept in partial sums (Lanes of four)
// over interleaved values and added in a fixed order at the end: one chain
// of additions is latency-bound (a 33 x 33 dot product took 0.8-0.9 us,
// 0.4-0.6 us in two sets of lanes), and the order is the same whatever the
// vector width.
#pragma once

#include <cstddef>
#include <cstring>

#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#define DPSFM_VECTOR_CLONES __attribute__((target_clones("avx2", "default")))
#else
#define DPSFM_VECTOR_CLONES
#endif

namespace dpsfm {

// Four doubles, and the four floats they are converted from (GCC and Clang
// vector types).
typedef double Lanes __attribute__((vector_size(32)));
typedef float LaneFloats __attribute__((vector_size(16)));

// Four consecutive floats from p as doubles, into *lanes (not returned: a
// 32-byte vector return would depend on the clone's ABI).
inline void LoadLanes(const float* p, Lanes* lanes) {
  LaneFloats floats;
  std::memcpy(&floats, p, sizeof(floats));
  *lanes = __builtin_convertvector(floats, Lanes);
}

// The sum of the four partial sums, in the fixed order.
inline double LanesTotal(const Lanes& sums) {
  return (sums[0] + sums[1]) + (sums[2] + sums[3]);
}

// sum a[i] b[i] over count floats, in double, in lanes.
double DotInLanes(const float* a, const float* b, size_t count);

}  // namespace dpsfm
