/* VECTOR_CLONES: a function the compiled loops want vectorized for the CPU at hand. GCC on x86-64
 * Linux builds it three times, for AVX-512 (x86-64-v4), for AVX2 and for any x86-64, and picks
 * one when the module loads. The loops it marks do the same IEEE operations (or integer ones)
 * whichever is picked: setup.py's flags forbid fused multiply-add and fast math, so each clone
 * gives the same bits. POVAGENT_ONE_BUILD builds the generic loop alone (the tests compare it,
 * and the AVX2 code built with -mavx2, with the installed loops). */
#ifndef POVAGENT_VECTOR_CLONES_H
#define POVAGENT_VECTOR_CLONES_H

#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__) && defined(__linux__) && !defined(POVAGENT_ONE_BUILD)
#define VECTOR_CLONES __attribute__((target_clones("arch=x86-64-v4", "avx2", "default")))
#else
#define VECTOR_CLONES
#endif

#endif
