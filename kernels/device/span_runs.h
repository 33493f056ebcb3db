/* SPDX-License-Identifier: BSD-3-Clause */
/* Span work per region (RM_REGION_OWNED, device.h): how a work-item of a span kernel takes its
 * spans. The host grouped the batch's span records by region into runs (rm_span_run, longest
 * first); each work-item takes the next whole run from a shared cursor as it comes free and walks
 * its spans in ray order, so it is the only writer of that region's voxels during the launch.
 * Shared by the occupancy and NDT span kernels. */
#ifndef RAYMAP_KERNELS_DEVICE_SPAN_RUNS_H
#define RAYMAP_KERNELS_DEVICE_SPAN_RUNS_H

#include "../common/batch.h"
#include "device.h"

/* A work-item's place in its current run: spans [next, end) are still to walk. */
typedef struct rm_run_cursor {
  rm_u32 next;
  rm_u32 end;
} rm_run_cursor;

RM_DEVICE_FN rm_run_cursor rm_run_cursor_make(void) {
  rm_run_cursor c;
  c.next = 0u;
  c.end = 0u;
  return c;
}

/* Sets *span to the work-item's next span record, taking the next of the `run_count` runs from
 * `next_run` when its run is done. Returns 0 when every run has been taken. */
RM_DEVICE_FN int rm_next_owned_span(rm_run_cursor* c, const RM_GLOBAL rm_span_run* runs,
                                    RM_ATOMIC_GLOBAL rm_u32* next_run, rm_u32 run_count,
                                    rm_u32* span) {
  while (c->next == c->end) {
    rm_u32 r = rm_atomic_add_u32(next_run, 1u);
    if (r >= run_count) {
      return 0;
    }
    c->next = runs[r].first;
    c->end = runs[r].first + runs[r].count;
  }
  *span = c->next;
  c->next += 1u;
  return 1;
}

#endif /* RAYMAP_KERNELS_DEVICE_SPAN_RUNS_H */
