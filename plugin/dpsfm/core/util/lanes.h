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

// Pointers whose caller has checked that they do not overlap, declared so
// for the vectoriser (GCC, Clang and MSVC spell it __restrict); nothing
// relies on it for what is computed.
#if defined(__GNUC__) || defined(_MSC_VER)
#define DPSFM_RESTRICT __restrict
#else
#define DPSFM_RESTRICT
#endif

namespace dpsfm {

// Four doubles: partial sums kept apart, each lane its own chain of IEEE
// operations, so the bits depend neither on the vector width nor on the
// compiler, provided nothing is contracted into FMAs (dp-sfm is built with
// -ffp-contract=off, CMakeLists.txt). Two forms with the same operations:
// - PortableLanes: plain C++ for any compiler;
// - VectorLanes: GCC's and Clang's vector extension, compiled to one AVX2 or
//   two SSE2 (NEON) operations. GCC 12 did not vectorise PortableLanes'
//   loops inside MomentsOfValues (intensity_loss.cc), which then took twice
//   as long.
// Lanes is the second where the compiler has it; lanes_test checks that
// both give the same bits.
struct PortableLanes {
  double v[4] = {0, 0, 0, 0};

  double& operator[](int k) { return v[k]; }
  double operator[](int k) const { return v[k]; }
  PortableLanes& operator+=(const PortableLanes& other) {
    for (int k = 0; k < 4; ++k) v[k] += other.v[k];
    return *this;
  }
};

inline PortableLanes operator+(PortableLanes a, const PortableLanes& b) {
  return a += b;
}

inline PortableLanes operator*(const PortableLanes& a,
                               const PortableLanes& b) {
  PortableLanes product;
  for (int k = 0; k < 4; ++k) product.v[k] = a.v[k] * b.v[k];
  return product;
}

// Four consecutive floats from p as doubles, into *lanes.
inline void LoadLanes(const float* p, PortableLanes* lanes) {
  for (int k = 0; k < 4; ++k) lanes->v[k] = p[k];
}

#if defined(__GNUC__)
typedef double VectorLanes __attribute__((vector_size(32)));
typedef float VectorLaneFloats __attribute__((vector_size(16)));

// Not returned: a 32-byte vector return would depend on the AVX2 clone's
// ABI (DPSFM_VECTOR_CLONES).
inline void LoadLanes(const float* p, VectorLanes* lanes) {
  VectorLaneFloats floats;
  std::memcpy(&floats, p, sizeof(floats));
  *lanes = __builtin_convertvector(floats, VectorLanes);
}

using Lanes = VectorLanes;
#else
using Lanes = PortableLanes;
#endif

// The sum of the four partial sums, in the fixed order.
template <typename L>
double LanesTotal(const L& sums) {
  return (sums[0] + sums[1]) + (sums[2] + sums[3]);
}

// sum a[i] b[i] over count floats, in double, in lanes of type L (Lanes
// or PortableLanes): two sets of lanes, eight values a step, since one
// set's additions would wait on each other.
template <typename L>
double DotInLanesOf(const float* a, const float* b, size_t count) {
  L low{}, high{};
  size_t i = 0;
  for (; i + 8 <= count; i += 8) {
    L u, v;
    LoadLanes(a + i, &u);
    LoadLanes(b + i, &v);
    low += u * v;
    LoadLanes(a + i + 4, &u);
    LoadLanes(b + i + 4, &v);
    high += u * v;
  }
  for (; i < count; ++i) low[0] += static_cast<double>(a[i]) * b[i];
  return LanesTotal(low + high);
}

// DotInLanesOf<Lanes>, compiled for AVX2 and the baseline
// (DPSFM_VECTOR_CLONES).
double DotInLanes(const float* a, const float* b, size_t count);

}  // namespace dpsfm
