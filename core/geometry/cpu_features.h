#pragma once

#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>
#define CBLOX_HAVE_X86 1
#endif

namespace cblox {

/// True when this CPU has AVX2 (asked once, then cached). The AVX2 paths (integrators, FAST,
/// rotated BRIEF) are compiled with target attributes and chosen at run time with this.
/// Thread-safe.
inline bool cpuHasAvx2() {
#if CBLOX_HAVE_X86
  static const bool has = __builtin_cpu_supports("avx2");
  return has;
#else
  return false;
#endif
}

/// True when this CPU has AVX2 and FMA (asked once, then cached). Thread-safe.
inline bool cpuHasAvx2Fma() {
#if CBLOX_HAVE_X86
  static const bool has = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
  return has;
#else
  return false;
#endif
}

}  // namespace cblox
