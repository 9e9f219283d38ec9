// The number of threads a core loop runs on. The core does not link COLMAP,
// so it cannot use colmap::GetEffectiveNumThreads; this is its twin for
// OpenMP (which honours OMP_NUM_THREADS). The COLMAP layer uses COLMAP's.
#pragma once

#include <exception>
#include <vector>

#ifdef _OPENMP
#include <omp.h>
#endif

namespace dpsfm {

// num_threads > 0 as given; otherwise (-1: "all") every thread OpenMP offers.
inline int EffectiveNumThreads(int num_threads) {
  if (num_threads > 0) return num_threads;
#ifdef _OPENMP
  return omp_get_max_threads();
#else
  return 1;
#endif
}

// body(i) for i in [0, n) on EffectiveNumThreads(num_threads) OpenMP
// threads. An exception may not leave a parallel region: the first (by
// index) that a body throws is rethrown after the loop.
template <typename Body>
void ParallelFor(int n, int num_threads, const Body& body) {
  std::vector<std::exception_ptr> failures(n);
#ifdef _OPENMP
  const int threads = EffectiveNumThreads(num_threads);
#pragma omp parallel for num_threads(threads) schedule(dynamic)
#endif
  for (int i = 0; i < n; ++i) {
    try {
      body(i);
    } catch (...) {
      failures[i] = std::current_exception();
    }
  }
  for (const std::exception_ptr& failure : failures) {
    if (failure) std::rethrow_exception(failure);
  }
}

}  // namespace dpsfm
