// Element-wise loops compiled twice, for AVX2 and for the x86-64 baseline
// (SSE2), the loader picking one for the machine (GNU ifunc): the compiler
// vectorises them four floats or doubles at a time where the baseline does
// two. Neither clone brings FMA to contract operations into, so both
// compute the same IEEE operations in the same order: the bits do not
// depend on the clone. Other compilers and machines get one plain version.
#pragma once

#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#define DPSFM_VECTOR_CLONES __attribute__((target_clones("avx2", "default")))
#else
#define DPSFM_VECTOR_CLONES
#endif
