/* SPDX-License-Identifier: BSD-3-Clause */
/* What every integration kernel shares about bounded atomic updates and their counters: the
 * compare-and-swap retry bound, and the batch counters (voxel visits in RM_COUNTER_BUCKETS
 * buckets, updates given up in RM_COUNTER_DROPPED; layout in kernels/common/batch.h). */
#ifndef RAYMAP_KERNELS_DEVICE_COUNTERS_H
#define RAYMAP_KERNELS_DEVICE_COUNTERS_H

#include "../common/batch.h"
#include "device.h"

/* Compare-and-swap attempts per miss before the update is given up (and counted). */
#define RM_CAS_RETRY_LIMIT 64

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

#endif /* RAYMAP_KERNELS_DEVICE_COUNTERS_H */
