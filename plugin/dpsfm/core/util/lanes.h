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

#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#define DPSFM_VECTOR_CLONES __attribute__((target_clones("avx2", "default")))
#else
#define DPSFM_VECTOR_CLONES
#endif

// Pointers whose caller has checked that they do not overlap, declared so
// for the vectoriser (GCC, Clang and MSVC spell it __restrict); nothing
// relies on it for what is computed.
#if defined(__GNUC__) || defined(_MSC_VER)
#define DPSFM_RESTRICT __restrict
#else
#define DPSFM_RESTRICT
#endif

namespace dpsfm {

// Four doubles: partial sums kept apart. Plain C++ whose element-wise loops
// GCC and Clang vectorise (one AVX2 or two SSE2 operations each, checked in
// the assembly of MomentsOfValues and DotInLanes); each lane is its own
// chain of IEEE operations, so the bits depend neither on the vector width
// nor on the compiler, provided none of it is contracted into FMAs (the
// core is built with -ffp-contract=off, plugin/CMakeLists.txt).
struct Lanes {
  double v[4] = {0, 0, 0, 0};

  double& operator[](int k) { return v[k]; }
  double operator[](int k) const { return v[k]; }
  Lanes& operator+=(const Lanes& other) {
    for (int k = 0; k < 4; ++k) v[k] += other.v[k];
    return *this;
  }
};

inline Lanes operator+(Lanes a, const Lanes& b) { return a += b; }

inline Lanes operator*(const Lanes& a, const Lanes& b) {
  Lanes product;
  for (int k = 0; k < 4; ++k) product.v[k] = a.v[k] * b.v[k];
  return product;
}

// Four consecutive floats from p as doubles, into *lanes.
inline void LoadLanes(const float* p, Lanes* lanes) {
  for (int k = 0; k < 4; ++k) lanes->v[k] = p[k];
}

// The sum of the four partial sums, in the fixed order.
inline double LanesTotal(const Lanes& sums) {
  return (sums.v[0] + sums.v[1]) + (sums.v[2] + sums.v[3]);
}

// sum a[i] b[i] over count floats, in double, in lanes.
double DotInLanes(const float* a, const float* b, size_t count);

}  // namespace dpsfm
