// Four lanes of doubles for the AVX2 kernels (GCC's vector extensions) and their operations,
// compiled for AVX2 like their callers: the ray kernels (ray_sweep.cpp) and the sweep's
// distances four points at a time (sweep.cpp). Each kernel keeps the scalar code's operations
// in the same order (no fused multiply-add), so the same bits. Private to the removal library.
#pragma once

#include <cstring>

namespace vcut::removal::detail {

#if defined(__x86_64__)
// Whether the processor runs AVX2.
inline const bool kHaveAvx2 = (__builtin_cpu_init(), __builtin_cpu_supports("avx2"));

typedef double v4d __attribute__((vector_size(32)));
typedef long v4i __attribute__((vector_size(32)));  // what comparing two v4d gives
#define VCUT_AVX2 __attribute__((target("avx2"), always_inline)) inline
VCUT_AVX2 v4d all(double x) { return v4d{x, x, x, x}; }
VCUT_AVX2 v4d vload(const double* p) {  // p[0 .. 3], any alignment
  v4d x;
  std::memcpy(&x, p, sizeof x);
  return x;
}
VCUT_AVX2 v4d select(v4i mask, v4d a, v4d b) { return mask ? a : b; }
VCUT_AVX2 v4d vmin(v4d current, v4d a) { return a < current ? a : current; }  // std::min(current, a)
VCUT_AVX2 v4d vmax(v4d current, v4d a) { return current < a ? a : current; }  // std::max(current, a)
VCUT_AVX2 v4d vsqrt(v4d x) { return __builtin_ia32_sqrtpd256(x); }
VCUT_AVX2 bool any_lane(v4i mask) { return (mask[0] | mask[1] | mask[2] | mask[3]) != 0; }  // some lane set
VCUT_AVX2 v4d vabs(v4d x) { return x < 0.0 ? -x : x; }  // std::abs but for -0.0 (its sign only)
#else
inline const bool kHaveAvx2 = false;
#endif

}  // namespace vcut::removal::detail
