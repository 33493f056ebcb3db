/* SPDX-License-Identifier: BSD-3-Clause */
/* What every integration kernel shares about bounded atomic updates and their counters: the
 * compare-and-swap retry bound, the plain miss and the float addition by compare-and-swap, and
 * the batch counters (voxel visits in RM_COUNTER_BUCKETS buckets, updates given up in
 * RM_COUNTER_DROPPED; layout in kernels/common/batch.h). */
#ifndef RAYMAP_KERNELS_DEVICE_COUNTERS_H
#define RAYMAP_KERNELS_DEVICE_COUNTERS_H

#include "../common/batch.h"
#include "../common/occupancy.h"
#include "device.h"

/* Compare-and-swap attempts per update before it is given up (and counted). Each failed attempt
 * means another work-item's update of the same word went in, so the loop always makes progress;
 * the bound is a last resort only, and it must exceed the number of updates that can race for one
 * word: on a GPU thousands of lanes of one launch update a sensor's own voxel (64 tries were
 * enough on PoCL's few threads, not there). */
#define RM_CAS_RETRY_LIMIT (1 << 20)

#if defined(RM_HAVE_INT64_ATOMICS)
typedef rm_u64 rm_counter;
RM_DEVICE_FN void rm_count(RM_ATOMIC_GLOBAL rm_counter* counters, rm_u32 which, rm_u32 amount) {
  (void)rm_atomic_add_u64(counters + which, (rm_u64)amount);
}
#else
/* 32-bit counters: the host sizes batches so that no bucket can wrap within one batch. */
typedef rm_u32 rm_counter;
RM_DEVICE_FN void rm_count(RM_ATOMIC_GLOBAL rm_counter* counters, rm_u32 which, rm_u32 amount) {
  (void)rm_atomic_add_u32(counters + which, amount);
}
#endif

/* Adds `value` to the float whose bits are `word` (decay rate: metres of path to a voxel's
 * traversal, kernels/common/decay.h). CUDA adds in one atomic; OpenCL 1.2 has no float atomics,
 * so it adds by compare-and-swap on the bits, retried at most RM_CAS_RETRY_LIMIT times (each
 * failure means another work-item's add went in). Returns 0 when the add was given up. Adding
 * zero (a walk through a voxel's edge or corner) writes nothing. */
RM_DEVICE_FN int rm_float_add_atomic(RM_ATOMIC_GLOBAL rm_u32* word, float value) {
#if defined(RM_HAVE_FLOAT_ATOMIC_ADD)
  if (value != 0.0f) {
    rm_atomic_add_f32(word, value);
  }
  return 1;
#else
  rm_u32 old;
  int attempt;
  if (value == 0.0f) {
    return 1;
  }
  old = rm_load_u32(word);
  for (attempt = 0; attempt < RM_CAS_RETRY_LIMIT; ++attempt) {
    rm_u32 seen = rm_voxel_cas_u32(word, old, rm_as_u32(rm_as_float(old) + value));
    if (seen == old) {
      return 1;
    }
    old = seen;
  }
  return 0;
#endif
}

/* Applies a plain miss to an occupancy word (occupancy: an untagged one) whose last seen bits are
 * `old`, with bounded compare-and-swap. Returns 0 when the update was given up. */
RM_DEVICE_FN int rm_occupancy_miss_atomic(RM_ATOMIC_GLOBAL rm_u32* word, rm_u32 old,
                                          rm_occupancy_params p) {
  int attempt;
  for (attempt = 0; attempt < RM_CAS_RETRY_LIMIT; ++attempt) {
    float value = rm_as_float(old);
    float updated = rm_occupancy_miss(value, p);
    rm_u32 seen;
    if (updated == value) {
      return 1;
    }
    seen = rm_voxel_cas_u32(word, old, rm_as_u32(updated));
    if (seen == old) {
      return 1;
    }
    old = seen;
  }
  return 0;
}

#endif /* RAYMAP_KERNELS_DEVICE_COUNTERS_H */
