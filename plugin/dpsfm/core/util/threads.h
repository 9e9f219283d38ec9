// The number of threads a core loop runs on. The core does not link COLMAP,
// so it cannot use colmap::GetEffectiveNumThreads; this is its twin for
// OpenMP (which honours OMP_NUM_THREADS). The COLMAP layer uses COLMAP's.
#pragma once

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

}  // namespace dpsfm
