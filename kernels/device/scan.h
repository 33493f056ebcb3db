/* SPDX-License-Identifier: BSD-3-Clause */
/* Prefix sums and a stable radix sort over 32-bit words, written once for OpenCL C 1.2 and CUDA:
 * what the device planner (plan.h) needs to place span records and group samples without the
 * host. Portable on purpose: the same code runs on PoCL in CI and on a GPU, so what CI proves is
 * what the GPU runs.
 *
 * Every kernel here works in tiles of RM_PLAN_TILE elements, one tile per work-group of
 * RM_PLAN_GROUP work-items, each work-item RM_PLAN_ITEMS consecutive elements. Arrays longer than
 * one tile take several launches, which the host sequences (src/device/staging/device_planner):
 *  - scan: rm_scan_tile over the array (each tile's exclusive sums and its total), the same over
 *    the totals (recursively, until one tile), then rm_scan_add of each tile's offset;
 *  - radix sort, one pass per RM_RADIX_BITS key bits: rm_radix_histogram (each tile's bucket
 *    counts, bucket-major), a scan of the counts, rm_radix_scatter (each element to its bucket's
 *    place, tiles and elements in their order: stable). */
#ifndef RAYMAP_KERNELS_DEVICE_SCAN_H
#define RAYMAP_KERNELS_DEVICE_SCAN_H

#include "../common/plan_abi.h"
#include "device.h"

/* Exclusive prefix sum of a[0 .. RM_PLAN_GROUP) in local memory by the whole work-group (every
 * work-item calls it); returns the sum of all. Work-efficient up- and down-sweep (Blelloch). */
RM_DEVICE_FN rm_u32 rm_group_exclusive_scan(RM_LOCAL rm_u32* a, rm_u32 lid) {
  rm_u32 offset = 1u;
  rm_u32 d;
  rm_u32 total;
  for (d = RM_PLAN_GROUP >> 1; d > 0u; d >>= 1) {
    rm_group_barrier();
    if (lid < d) {
      rm_u32 ai = offset * (2u * lid + 1u) - 1u;
      rm_u32 bi = offset * (2u * lid + 2u) - 1u;
      a[bi] += a[ai];
    }
    offset <<= 1;
  }
  rm_group_barrier();
  total = a[RM_PLAN_GROUP - 1u];
  rm_group_barrier();
  if (lid == 0u) {
    a[RM_PLAN_GROUP - 1u] = 0u;
  }
  for (d = 1u; d < RM_PLAN_GROUP; d <<= 1) {
    offset >>= 1;
    rm_group_barrier();
    if (lid < d) {
      rm_u32 ai = offset * (2u * lid + 1u) - 1u;
      rm_u32 bi = offset * (2u * lid + 2u) - 1u;
      rm_u32 t = a[ai];
      a[ai] = a[bi];
      a[bi] += t;
    }
  }
  rm_group_barrier();
  return total;
}

/* Tile rm_group_id() of in[0 .. n): out gets the exclusive sums within the tile, tile_sums[tile]
 * the tile's total. `in` and `out` may be the same array. `partial`: RM_PLAN_GROUP local words. */
RM_DEVICE_FN void rm_scan_tile(rm_u32 n, const RM_GLOBAL rm_u32* in, RM_GLOBAL rm_u32* out,
                               RM_GLOBAL rm_u32* tile_sums, RM_LOCAL rm_u32* partial) {
  rm_u32 lid = rm_local_id();
  rm_u32 base = rm_group_id() * RM_PLAN_TILE + lid * RM_PLAN_ITEMS;
  rm_u32 v[RM_PLAN_ITEMS];
  rm_u32 sum = 0u;
  rm_u32 k;
  rm_u32 total;
  for (k = 0u; k < RM_PLAN_ITEMS; ++k) {
    v[k] = base + k < n ? in[base + k] : 0u;
    sum += v[k];
  }
  partial[lid] = sum;
  total = rm_group_exclusive_scan(partial, lid);
  sum = partial[lid];
  for (k = 0u; k < RM_PLAN_ITEMS; ++k) {
    if (base + k < n) {
      out[base + k] = sum;
    }
    sum += v[k];
  }
  if (lid == 0u) {
    tile_sums[rm_group_id()] = total;
  }
}

/* Adds tile rm_group_id()'s offset (the exclusive scan of the tile totals) to its elements. */
RM_DEVICE_FN void rm_scan_add_tile(rm_u32 n, RM_GLOBAL rm_u32* out,
                                   const RM_GLOBAL rm_u32* tile_offsets) {
  rm_u32 base = rm_group_id() * RM_PLAN_TILE + rm_local_id() * RM_PLAN_ITEMS;
  rm_u32 offset = tile_offsets[rm_group_id()];
  rm_u32 k;
  for (k = 0u; k < RM_PLAN_ITEMS; ++k) {
    if (base + k < n) {
      out[base + k] += offset;
    }
  }
}

/* Radix sort pass, step 1: tile rm_group_id()'s count of each bucket of key bits
 * [shift, shift + RM_RADIX_BITS) into hist[bucket * tiles + tile]. `counts`: RM_RADIX_BUCKETS
 * local words. */
RM_DEVICE_FN void rm_radix_histogram_tile(rm_u32 n, rm_u32 shift, rm_u32 tiles,
                                          const RM_GLOBAL rm_u32* keys, RM_GLOBAL rm_u32* hist,
                                          volatile RM_LOCAL rm_u32* counts) {
  rm_u32 lid = rm_local_id();
  rm_u32 base = rm_group_id() * RM_PLAN_TILE + lid * RM_PLAN_ITEMS;
  rm_u32 k;
  if (lid < RM_RADIX_BUCKETS) {
    counts[lid] = 0u;
  }
  rm_group_barrier();
  for (k = 0u; k < RM_PLAN_ITEMS; ++k) {
    if (base + k < n) {
      (void)rm_local_atomic_add(counts + ((keys[base + k] >> shift) & (RM_RADIX_BUCKETS - 1u)), 1u);
    }
  }
  rm_group_barrier();
  if (lid < RM_RADIX_BUCKETS) {
    hist[lid * tiles + rm_group_id()] = counts[lid];
  }
}

/* Radix sort pass, step 3: moves tile rm_group_id()'s elements to their places. `bases`: the
 * exclusive scan of the pass's histogram (where each bucket of each tile starts). Within a tile
 * an element's place among its bucket is the count of that bucket's elements before it: the
 * work-items' per-bucket counts, bucket-major in `flat` (RM_RADIX_BUCKETS * RM_PLAN_GROUP local
 * words), scanned as one array, plus its own earlier elements. `partial`: RM_PLAN_GROUP local
 * words. */
RM_DEVICE_FN void rm_radix_scatter_tile(rm_u32 n, rm_u32 shift, rm_u32 tiles,
                                        const RM_GLOBAL rm_u32* keys_in,
                                        const RM_GLOBAL rm_u32* vals_in,
                                        const RM_GLOBAL rm_u32* bases, RM_GLOBAL rm_u32* keys_out,
                                        RM_GLOBAL rm_u32* vals_out, RM_LOCAL rm_u32* flat,
                                        RM_LOCAL rm_u32* partial) {
  rm_u32 lid = rm_local_id();
  rm_u32 tile = rm_group_id();
  rm_u32 base = tile * RM_PLAN_TILE + lid * RM_PLAN_ITEMS;
  rm_u32 key[RM_PLAN_ITEMS];
  rm_u32 val[RM_PLAN_ITEMS];
  rm_u32 bucket[RM_PLAN_ITEMS];
  rm_u32 k;
  rm_u32 j;
  rm_u32 sum = 0u;
  for (j = 0u; j < RM_RADIX_BUCKETS; ++j) {
    flat[j * RM_PLAN_GROUP + lid] = 0u; /* this work-item's column */
  }
  for (k = 0u; k < RM_PLAN_ITEMS; ++k) {
    key[k] = 0u;
    val[k] = 0u;
    bucket[k] = 0u;
    if (base + k < n) {
      key[k] = keys_in[base + k];
      val[k] = vals_in[base + k];
      bucket[k] = (key[k] >> shift) & (RM_RADIX_BUCKETS - 1u);
      flat[bucket[k] * RM_PLAN_GROUP + lid] += 1u;
    }
  }
  rm_group_barrier();
  /* Exclusive scan of all RM_RADIX_BUCKETS * RM_PLAN_GROUP counts: work-item lid scans its
   * RM_RADIX_BUCKETS consecutive words, the work-group scans their sums. */
  for (j = 0u; j < RM_RADIX_BUCKETS; ++j) {
    sum += flat[lid * RM_RADIX_BUCKETS + j];
  }
  partial[lid] = sum;
  (void)rm_group_exclusive_scan(partial, lid);
  sum = partial[lid];
  for (j = 0u; j < RM_RADIX_BUCKETS; ++j) {
    rm_u32 count = flat[lid * RM_RADIX_BUCKETS + j];
    flat[lid * RM_RADIX_BUCKETS + j] = sum;
    sum += count;
  }
  rm_group_barrier();
  for (k = 0u; k < RM_PLAN_ITEMS; ++k) {
    if (base + k < n) {
      rm_u32 b = bucket[k];
      rm_u32 rank = flat[b * RM_PLAN_GROUP + lid] - flat[b * RM_PLAN_GROUP];
      rm_u32 place;
      for (j = 0u; j < k; ++j) {
        rank += bucket[j] == b ? 1u : 0u;
      }
      place = bases[b * tiles + tile] + rank;
      keys_out[place] = key[k];
      vals_out[place] = val[k];
    }
  }
}

#endif /* RAYMAP_KERNELS_DEVICE_SCAN_H */
