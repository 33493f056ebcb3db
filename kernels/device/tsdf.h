/* SPDX-License-Identifier: BSD-3-Clause */
/* TSDF maps on a device: what a span does to the TSDF layer, by the rules of
 * kernels/common/tsdf.h, the same updates the CPU's tsdfSpan (src/map/cpu_voxel_ops.hpp) makes.
 * Called by the occupancy span kernel when rm_integrate_params.has_tsdf is set (a uniform branch:
 * a TSDF map has no occupancy layer and its rays no hits, so that is all its batches do).
 *
 * Each voxel update reads the (distance, weight) pair, fuses the ray in and writes both back as
 * one: with a 64-bit compare-and-swap where the device has 64-bit atomics (CUDA always,
 * OpenCL with cl_khr_int64_base_atomics), retried at most RM_CAS_RETRY_LIMIT times (a failed
 * compare-and-swap means another work-item's update went in). Without them, the sign bit of the
 * weight word (weights are never negative) is a per-voxel lock taken with a 32-bit
 * compare-and-swap, tried at most RM_TSDF_LOCK_SPIN_LIMIT times: the holder reads the distance,
 * writes the fused distance and releases by writing the fused weight, in straight-line code. An
 * update given up under contention is counted in RM_COUNTER_DROPPED by the caller, never lost
 * silently. Updates of one voxel by several rays in one batch land in any order: the averages
 * differ from the CPU's by float rounding only. With span work per region (RM_REGION_OWNED,
 * device.h) a voxel has one writer and its updates come in ray order: it is updated exactly as on
 * the CPU (rm_tsdf_update), with plain reads and writes.
 *
 * Every walk skips the distance of free space, as the CPU's does: a voxel the ray enters far
 * enough in front of the surface (rm_tsdf_free_bound) is updated at +tau, the update its
 * computed distance would give after the clamp. */
#ifndef RAYMAP_KERNELS_DEVICE_TSDF_H
#define RAYMAP_KERNELS_DEVICE_TSDF_H

#include "../common/batch.h"
#include "../common/line_walk.h"
#include "../common/span_walk.h"
#include "../common/tsdf.h"
#include "counters.h"
#include "device.h"

#define RM_TSDF_LOCK_BIT 0x80000000u
/* Tries for a voxel's lock before the update is given up. A holder keeps it for a few
 * instructions, so waits are short on a GPU, where a work-item that holds it keeps running. On a
 * CPU device (PoCL) the holder's thread can be preempted inside those instructions for a
 * scheduler slice or more (measured: 4M tries, a few milliseconds, were not enough on a loaded
 * 2-core machine), so the bound is about a second of spinning: a last resort, never a wait. */
#define RM_TSDF_LOCK_SPIN_LIMIT 0x10000000u

/* Fuses a ray at signed distance sdf into pair i of the layer (word 2i: distance, 2i + 1:
 * weight). Returns 0 when the update was given up. */
RM_DEVICE_FN int rm_tsdf_update_atomic(RM_ATOMIC_GLOBAL rm_u32* tsdf, rm_u32 i, float sdf,
                                       rm_tsdf_params p) {
#if defined(RM_REGION_OWNED)
  /* One writer per voxel: the CPU's update (rm_tsdf_update, with its free-space shortcut) on a
   * private copy, and only the words that changed written back (a voxel of free space crossed
   * again at full weight, most of a steady map, writes nothing). */
  RM_ATOMIC_GLOBAL rm_u32* pair = tsdf + i + i; /* not 2u * i: wraps past 2^31 voxels */
  rm_u32 distance_bits = pair[0];
  rm_u32 weight_bits = pair[1];
  rm_tsdf_voxel v;
  v.distance = rm_as_float(distance_bits);
  v.weight = rm_as_float(weight_bits);
  rm_tsdf_update(&v, sdf, p);
  if (rm_as_u32(v.distance) != distance_bits) {
    pair[0] = rm_as_u32(v.distance);
  }
  if (rm_as_u32(v.weight) != weight_bits) {
    pair[1] = rm_as_u32(v.weight);
  }
  return 1;
#else
  float w;
  if (!rm_tsdf_in_reach(sdf, p)) {
    return 1;
  }
  w = rm_tsdf_weight(sdf, p);
#if defined(RM_HAVE_INT64_ATOMICS)
  {
    RM_ATOMIC_GLOBAL rm_u64* pair = (RM_ATOMIC_GLOBAL rm_u64*)(tsdf + i + i);
    rm_u64 old = rm_load_u64(pair);
    int attempt;
    for (attempt = 0; attempt < RM_CAS_RETRY_LIMIT; ++attempt) {
      rm_tsdf_voxel v;
      rm_tsdf_voxel fused;
      rm_u64 desired;
      rm_u64 seen;
      /* Little-endian: the distance (first member) is the low word. */
      v.distance = rm_as_float((rm_u32)(old & 0xFFFFFFFFu));
      v.weight = rm_as_float((rm_u32)(old >> 32));
      fused = rm_tsdf_fuse(v, sdf, w, p);
      desired = (rm_u64)rm_as_u32(fused.distance) | ((rm_u64)rm_as_u32(fused.weight) << 32);
      if (desired == old) {
        return 1;
      }
      seen = rm_voxel_cas_u64(pair, old, desired);
      if (seen == old) {
        return 1;
      }
      old = seen;
    }
    return 0;
  }
#else
  {
    RM_ATOMIC_GLOBAL rm_u32* distance = tsdf + i + i; /* not 2u * i: wraps past 2^31 voxels */
    RM_ATOMIC_GLOBAL rm_u32* weight = distance + 1;
    int done = 0;
    rm_u32 spins;
    /* The critical section sits inside the loop body and every path meets again at its end, so
     * on SIMT hardware the lock holder finishes in the same pass as the lanes that wait on it
     * (a holder that left the loop would wait for them at the function's end: a deadlock). */
    for (spins = 0u; done == 0 && spins < RM_TSDF_LOCK_SPIN_LIMIT; ++spins) {
      rm_u32 bits = rm_load_u32(weight);
      if ((bits & RM_TSDF_LOCK_BIT) == 0u &&
          rm_voxel_cas_u32(weight, bits, bits | RM_TSDF_LOCK_BIT) == bits) {
        rm_tsdf_voxel v;
        rm_tsdf_voxel fused;
        rm_global_fence();
        v.weight = rm_as_float(bits);
        v.distance = rm_as_float(rm_voxel_xchg_u32(distance, 0u));
        fused = rm_tsdf_fuse(v, sdf, w, p);
        (void)rm_voxel_xchg_u32(distance, rm_as_u32(fused.distance));
        rm_global_fence();
        (void)rm_voxel_xchg_u32(weight, rm_as_u32(fused.weight)); /* releases the voxel */
        done = 1;
      }
    }
    return done;
  }
#endif
#endif /* RM_REGION_OWNED */
}

/* Walks `count` voxels of span walk `s` (as rm_span_walk_init left it) and fuses the ray into each.
 * `base`: the span's region in the layer (slot * voxels_per_region). Returns the updates given
 * up. */
RM_DEVICE_FN rm_u32 rm_tsdf_span(RM_ATOMIC_GLOBAL rm_u32* tsdf, rm_u32 base, rm_span_walk s,
                                 rm_i32 count, const rm_line_walk_ray* walk_ray,
                                 int sample_is_start, float end_sdf, rm_tsdf_params p) {
  rm_tsdf_ray ray = rm_tsdf_ray_make(walk_ray, sample_is_start, end_sdf);
  float free_bound = rm_tsdf_free_bound(&ray, p);
  rm_u32 dropped = 0u;
  rm_i32 k;
  for (k = 0; k < count; ++k) {
    rm_u32 i = base + (k == 0 ? RM_U32(s.index) : rm_span_walk_advance(&s));
    /* Free space (most voxels of a ray) needs no distance: its update is the one at +tau. */
    float sdf = rm_tsdf_is_free(rm_line_walk_t_enter(&s.walk), free_bound, sample_is_start)
                    ? p.truncation
                    : rm_tsdf_sdf(&ray, rm_span_walk_voxel(&s), p.resolution);
    dropped += rm_tsdf_update_atomic(tsdf, i, sdf, p) ? 0u : 1u;
  }
  return dropped;
}

#endif /* RAYMAP_KERNELS_DEVICE_TSDF_H */
