/* SPDX-License-Identifier: BSD-3-Clause */
/* The translation header for device code: kernel qualifiers, work-item indices and atomics for
 * OpenCL C 1.2 and CUDA, so that the headers in kernels/device are written once and the OpenCL
 * (.cl) and CUDA (.cu) entry points are thin wrappers. Host C++ never includes this header.
 *
 * 64-bit atomics: CUDA always has them; OpenCL 1.2 only with cl_khr_int64_base_atomics, which
 * the host detects at run time and announces by defining RM_HAVE_INT64_ATOMICS when it builds the
 * program. Everything that uses them has a 32-bit path. */
#ifndef RAYMAP_KERNELS_DEVICE_DEVICE_H
#define RAYMAP_KERNELS_DEVICE_DEVICE_H

#include "../common/portable.h"

#if defined(__OPENCL_C_VERSION__)
/* ---- OpenCL C 1.2 ---- */
#define RM_DEVICE_FN static inline
#define RM_DEVICE_COLD_FN static __attribute__((noinline))
#define RM_KERNEL __kernel
/* Made for one map mode (kernels/common/map_mode.h): in OpenCL the program is built for one
 * mode, RM_MAP_MODE is a -D, and these are plain functions and kernels. */
#define RM_MODE_FN static inline
#define RM_MODE_KERNEL __kernel
#define RM_MODE_CALL(fn) fn
#define RM_GLOBAL __global
/* Memory updated by atomics from several work-items. In a program whose span kernel gives each
 * region to one work-item (RM_REGION_OWNED, below) only the batch counters are: voxel layers are
 * plain memory there, so the compiler may keep a voxel in a register between reads. */
#if defined(RM_REGION_OWNED)
#define RM_ATOMIC_GLOBAL __global
#else
#define RM_ATOMIC_GLOBAL volatile __global
#endif

RM_DEVICE_FN rm_u32 rm_global_id(void) { return RM_U32(get_global_id(0)); }
RM_DEVICE_FN float rm_as_float(rm_u32 bits) { return as_float(bits); }
RM_DEVICE_FN rm_u32 rm_as_u32(float value) { return as_uint(value); }
RM_DEVICE_FN rm_u32 rm_atomic_cas_u32(RM_ATOMIC_GLOBAL rm_u32* p, rm_u32 expected, rm_u32 desired) {
  return atomic_cmpxchg(p, expected, desired);
}
RM_DEVICE_FN rm_u32 rm_atomic_max_u32(RM_ATOMIC_GLOBAL rm_u32* p, rm_u32 value) {
  return atomic_max(p, value);
}
RM_DEVICE_FN rm_u32 rm_atomic_add_u32(RM_ATOMIC_GLOBAL rm_u32* p, rm_u32 value) {
  return atomic_add(p, value);
}
RM_DEVICE_FN rm_u32 rm_atomic_xchg_u32(RM_ATOMIC_GLOBAL rm_u32* p, rm_u32 value) {
  return atomic_xchg(p, value);
}
/* Orders this work-item's global memory accesses before and after it. */
RM_DEVICE_FN void rm_global_fence(void) { mem_fence(CLK_GLOBAL_MEM_FENCE); }
RM_DEVICE_FN rm_u32 rm_atomic_min_u32(RM_ATOMIC_GLOBAL rm_u32* p, rm_u32 value) {
  return atomic_min(p, value);
}
RM_DEVICE_FN rm_u32 rm_atomic_or_u32(RM_ATOMIC_GLOBAL rm_u32* p, rm_u32 value) {
  return atomic_or(p, value);
}
/* Work-group primitives (the device planner's scans and sorts, kernels/device/plan.h): local
 * memory, the work-item's place in its group, and the group barrier. A kernel that uses them is
 * launched in groups of exactly the size it names (RM_GROUP_KERNEL). */
#define RM_LOCAL __local
#define RM_LOCAL_ARRAY(type, name, count) __local type name[count]
#define RM_GROUP_KERNEL(size) __kernel __attribute__((reqd_work_group_size(size, 1, 1)))
RM_DEVICE_FN rm_u32 rm_local_id(void) { return RM_U32(get_local_id(0)); }
RM_DEVICE_FN rm_u32 rm_group_id(void) { return RM_U32(get_group_id(0)); }
RM_DEVICE_FN void rm_group_barrier(void) { barrier(CLK_LOCAL_MEM_FENCE); }
RM_DEVICE_FN rm_u32 rm_local_atomic_add(volatile __local rm_u32* p, rm_u32 value) {
  return atomic_add(p, value);
}
#if defined(RM_HAVE_INT64_ATOMICS)
#pragma OPENCL EXTENSION cl_khr_int64_base_atomics : enable
typedef ulong rm_u64;
RM_DEVICE_FN rm_u64 rm_atomic_add_u64(RM_ATOMIC_GLOBAL rm_u64* p, rm_u64 value) {
  return atom_add(p, value);
}
RM_DEVICE_FN rm_u64 rm_atomic_cas_u64(RM_ATOMIC_GLOBAL rm_u64* p, rm_u64 expected, rm_u64 desired) {
  return atom_cmpxchg(p, expected, desired);
}
RM_DEVICE_FN rm_u64 rm_load_u64(RM_ATOMIC_GLOBAL rm_u64* p) { return *p; }
#endif

#elif defined(__CUDACC__)
/* ---- CUDA ---- */
#define RM_DEVICE_FN static inline __device__
#define RM_DEVICE_COLD_FN static __noinline__ __device__
#define RM_KERNEL extern "C" __global__
/* Made for one map mode (kernels/common/map_mode.h): in CUDA one source holds every mode's
 * kernels, templates over RM_MAP_MODE that the launchers instantiate once per mode. */
#define RM_MODE_FN              \
  template <rm_u32 RM_MAP_MODE> \
  static inline __device__
#define RM_MODE_KERNEL          \
  template <rm_u32 RM_MAP_MODE> \
  __global__
#define RM_MODE_CALL(fn) fn<RM_MAP_MODE>
#define RM_GLOBAL
#define RM_ATOMIC_GLOBAL
#ifndef RM_HAVE_INT64_ATOMICS
#define RM_HAVE_INT64_ATOMICS 1
#endif
typedef unsigned long long rm_u64;

RM_DEVICE_FN rm_u32 rm_global_id(void) { return blockIdx.x * blockDim.x + threadIdx.x; }
RM_DEVICE_FN float rm_as_float(rm_u32 bits) { return __uint_as_float(bits); }
RM_DEVICE_FN rm_u32 rm_as_u32(float value) { return __float_as_uint(value); }
RM_DEVICE_FN rm_u32 rm_atomic_cas_u32(rm_u32* p, rm_u32 expected, rm_u32 desired) {
  return atomicCAS(p, expected, desired);
}
RM_DEVICE_FN rm_u32 rm_atomic_max_u32(rm_u32* p, rm_u32 value) { return atomicMax(p, value); }
RM_DEVICE_FN rm_u32 rm_atomic_add_u32(rm_u32* p, rm_u32 value) { return atomicAdd(p, value); }
RM_DEVICE_FN rm_u32 rm_atomic_xchg_u32(rm_u32* p, rm_u32 value) { return atomicExch(p, value); }
RM_DEVICE_FN void rm_global_fence(void) { __threadfence(); }
RM_DEVICE_FN rm_u32 rm_atomic_min_u32(rm_u32* p, rm_u32 value) { return atomicMin(p, value); }
RM_DEVICE_FN rm_u32 rm_atomic_or_u32(rm_u32* p, rm_u32 value) { return atomicOr(p, value); }
#define RM_LOCAL
#define RM_LOCAL_ARRAY(type, name, count) __shared__ type name[count]
#define RM_GROUP_KERNEL(size) extern "C" __global__ __launch_bounds__(size)
RM_DEVICE_FN rm_u32 rm_local_id(void) { return threadIdx.x; }
RM_DEVICE_FN rm_u32 rm_group_id(void) { return blockIdx.x; }
RM_DEVICE_FN void rm_group_barrier(void) { __syncthreads(); }
RM_DEVICE_FN rm_u32 rm_local_atomic_add(volatile rm_u32* p, rm_u32 value) {
  return atomicAdd(const_cast<rm_u32*>(p), value);
}
RM_DEVICE_FN rm_u64 rm_load_u64(rm_u64* p) { return *(volatile rm_u64*)p; }
RM_DEVICE_FN rm_u64 rm_atomic_add_u64(rm_u64* p, rm_u64 value) { return atomicAdd(p, value); }
RM_DEVICE_FN rm_u64 rm_atomic_cas_u64(rm_u64* p, rm_u64 expected, rm_u64 desired) {
  return atomicCAS(p, expected, desired);
}
/* Float addition in one hardware atomic, to a word that holds a float's bits. OpenCL 1.2 has
 * none: counters.h adds by compare-and-swap there. */
#define RM_HAVE_FLOAT_ATOMIC_ADD 1
RM_DEVICE_FN void rm_atomic_add_f32(rm_u32* p, float value) { (void)atomicAdd((float*)p, value); }

#else
#error "kernels/device headers are device code: include them from .cl or .cu files only"
#endif

/* A fresh read of a word other work-items update (volatile in OpenCL, so it is not cached in a
 * register across a compare-and-swap loop). */
RM_DEVICE_FN rm_u32 rm_load_u32(RM_ATOMIC_GLOBAL rm_u32* p) {
#if defined(__CUDACC__)
  return *(volatile rm_u32*)p;
#else
  return *p;
#endif
}

/* Updates of voxel-layer words. The span kernels launched one work-item per span record share
 * voxels with other work-items and update them with atomics. A program built with
 * -DRM_REGION_OWNED (OpenCL on CPU devices, docs/architecture.md "Span work on CPU devices")
 * launches its span kernel one work-item per region instead: the host groups the batch's span
 * records by region, in ray order, and every voxel then has one writer during the launch. The
 * same update code does plain reads and writes there, which on a CPU device are several times
 * cheaper than locked instructions (each compare-and-swap below then succeeds at once). The batch
 * counters stay atomic (rm_atomic_*). */
#if defined(RM_REGION_OWNED)
#if defined(__CUDACC__)
#error "RM_REGION_OWNED is for OpenCL programs on CPU devices"
#endif
RM_DEVICE_FN rm_u32 rm_voxel_cas_u32(RM_ATOMIC_GLOBAL rm_u32* p, rm_u32 expected, rm_u32 desired) {
  rm_u32 seen = *p;
  if (seen == expected) {
    *p = desired;
  }
  return seen;
}
RM_DEVICE_FN rm_u32 rm_voxel_max_u32(RM_ATOMIC_GLOBAL rm_u32* p, rm_u32 value) {
  rm_u32 seen = *p;
  if (value > seen) {
    *p = value;
  }
  return seen;
}
RM_DEVICE_FN rm_u32 rm_voxel_add_u32(RM_ATOMIC_GLOBAL rm_u32* p, rm_u32 value) {
  rm_u32 seen = *p;
  *p = seen + value;
  return seen;
}
RM_DEVICE_FN rm_u32 rm_voxel_xchg_u32(RM_ATOMIC_GLOBAL rm_u32* p, rm_u32 value) {
  rm_u32 seen = *p;
  *p = value;
  return seen;
}
#if defined(RM_HAVE_INT64_ATOMICS)
RM_DEVICE_FN rm_u64 rm_voxel_cas_u64(RM_ATOMIC_GLOBAL rm_u64* p, rm_u64 expected, rm_u64 desired) {
  rm_u64 seen = *p;
  if (seen == expected) {
    *p = desired;
  }
  return seen;
}
#endif
#else
#define rm_voxel_cas_u32 rm_atomic_cas_u32
#define rm_voxel_max_u32 rm_atomic_max_u32
#define rm_voxel_add_u32 rm_atomic_add_u32
#define rm_voxel_xchg_u32 rm_atomic_xchg_u32
#define rm_voxel_cas_u64 rm_atomic_cas_u64
#endif

#endif /* RAYMAP_KERNELS_DEVICE_DEVICE_H */
