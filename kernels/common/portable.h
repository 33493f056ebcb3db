/* SPDX-License-Identifier: BSD-3-Clause */
/* Maps qualifiers, fixed-width types, casts and float helpers onto host C/C++, CUDA and OpenCL
 * C 1.2, so that the kernel headers beside this one are written once. */
#ifndef RAYMAP_KERNELS_COMMON_PORTABLE_H
#define RAYMAP_KERNELS_COMMON_PORTABLE_H

#if defined(__OPENCL_C_VERSION__)
/* ---- OpenCL C 1.2 ---- */
#define RAYMAP_FN static inline
#define RAYMAP_GLOBAL __global
typedef int rm_i32;
typedef uint rm_u32;
#define RM_F32(x) ((float)(x))
#define RM_F64(x) ((double)(x))
#define RM_I32(x) ((rm_i32)(x))
#define RM_U32(x) ((rm_u32)(x))
#define RM_FLOORF(x) floor(x)
#define RM_FABSF(x) fabs(x)
#define RM_FMINF(a, b) fmin((a), (b))
#define RM_FMAXF(a, b) fmax((a), (b))
#define RM_SQRTF(x) sqrt(x)
#define RM_INF INFINITY
#define RM_NAN NAN

#else
/* ---- host C, host C++ and CUDA C++ ---- */
#if defined(__cplusplus)
#include <cfloat>
#include <cmath>
#include <cstdint>
#else
#include <float.h>
#include <math.h>
#include <stdint.h>
#endif

#if defined(__CUDACC__)
#define RAYMAP_FN static inline __host__ __device__
#else
#define RAYMAP_FN static inline
#endif
#define RAYMAP_GLOBAL
typedef int32_t rm_i32;
typedef uint32_t rm_u32;

#if defined(__cplusplus)
/* C++ (host and CUDA): named casts keep -Wold-style-cast quiet and make each conversion visible. */
#define RM_F32(x) static_cast<float>(x)
#define RM_F64(x) static_cast<double>(x)
#define RM_I32(x) static_cast<rm_i32>(x)
#define RM_U32(x) static_cast<rm_u32>(x)
#else
#define RM_F32(x) ((float)(x))
#define RM_F64(x) ((double)(x))
#define RM_I32(x) ((rm_i32)(x))
#define RM_U32(x) ((rm_u32)(x))
#endif
#define RM_FLOORF(x) floorf(x)
#define RM_FABSF(x) fabsf(x)
/* Not fminf/fmaxf: without -ffinite-math-only GCC turns those into libm calls (their NaN rules
 * differ from the minss instruction), and the walk calls them on every step. Kernel inputs are
 * validated finite, so the comparison form is exact here. */
#define RM_FMINF(a, b) rm_minf((a), (b))
#define RM_FMAXF(a, b) rm_maxf((a), (b))
#define RM_SQRTF(x) sqrtf(x)
#define RM_INF INFINITY
#define RM_NAN NAN
#endif

/* Small vectors passed by value between the kernel helpers. Plain arrays-in-structs are legal in
 * C, C++, CUDA and OpenCL C and have the same layout everywhere (no float3 padding surprises). */
typedef struct rm_vec3f {
  float x;
  float y;
  float z;
} rm_vec3f;

typedef struct rm_vec3i {
  rm_i32 x;
  rm_i32 y;
  rm_i32 z;
} rm_vec3i;

RAYMAP_FN rm_vec3f rm_vec3f_make(float x, float y, float z) {
  rm_vec3f v;
  v.x = x;
  v.y = y;
  v.z = z;
  return v;
}

RAYMAP_FN rm_vec3i rm_vec3i_make(rm_i32 x, rm_i32 y, rm_i32 z) {
  rm_vec3i v;
  v.x = x;
  v.y = y;
  v.z = z;
  return v;
}

#if !defined(__OPENCL_C_VERSION__)
RAYMAP_FN float rm_minf(float a, float b) { return b < a ? b : a; }
RAYMAP_FN float rm_maxf(float a, float b) { return a < b ? b : a; }
#endif

/* floor() to an integer for |x| < 2^31. Without SSE4.1 (the x86-64 baseline) floorf is a libm
 * call, and the walk floors six values per region span. */
RAYMAP_FN rm_i32 rm_floor_i32(float x) {
  rm_i32 truncated = RM_I32(x);
  return truncated - ((x < RM_F32(truncated)) ? 1 : 0);
}

RAYMAP_FN rm_i32 rm_clamp_i32(rm_i32 v, rm_i32 lo, rm_i32 hi) {
  return v < lo ? lo : (v > hi ? hi : v);
}

RAYMAP_FN rm_i32 rm_abs_i32(rm_i32 v) { return v < 0 ? -v : v; }

RAYMAP_FN rm_i32 rm_sign_i32(rm_i32 v) { return (v > 0) - (v < 0); }

#endif /* RAYMAP_KERNELS_COMMON_PORTABLE_H */
