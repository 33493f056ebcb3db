/* SPDX-License-Identifier: BSD-3-Clause */
/* Planning a batch on the device: the bodies of the planning kernels, written once for OpenCL C
 * 1.2 and CUDA (entry points: plan_kernels.h). They produce what the host planner
 * (src/device/staging/batch_plan.cpp) produces, span for span, from the same walk
 * (kernels/common/region_walk.h), so the integration kernels cannot tell the two apart.
 *
 * Plan phase, for rays[0 .. n) (args.n):
 *  1. rm_plan_count_ray: each ray's spans inside the rolling window (counts[n] = 0);
 *  2. an exclusive scan of the counts: offsets[r] is ray r's first span record, offsets[n] all;
 *     rm_plan_cut_ray ends the batch before the first ray that might not fit max_spans records
 *     (by the regions it crosses, as the host planner decides), so no later ray is planned;
 *  3. rm_plan_emit_ray: each ray walks its regions again and writes its span records in walk
 *     order at offsets[r], so the records are in ray order as the host writes them. Each region
 *     goes into the batch's region table (open addressing on its relative key, 32-bit
 *     compare-and-swap), which keeps per region the first span record (atomic min: the order of
 *     first appearance), the span records and the samples; a span record holds its region's table
 *     entry where its slot will go. A ray's sample voxel becomes a hit key (entry * voxels per
 *     region + voxel index, or NONE). Rays from the cut on write nothing;
 *  4. a stable radix sort of the (hit key, ray) pairs, then rm_plan_group_head and a scan number
 *     the distinct keys and rm_plan_group_build writes one rm_hit_group per voxel with samples:
 *     its table entry where the slot will go, and its rays in ray order (the sorted rays are the
 *     batch's hit-ray list);
 *  5. rm_plan_compact_entry lists the table's regions for the host, rm_plan_finish the sizes.
 * The host reads the status and the region list back, places each region in the device cache in
 * the order of first appearance (as the host planner does) and uploads a slot per region.
 * Resolve phase: rm_plan_resolve_region maps each table entry to its slot (and its run's rank,
 * for span work per region), rm_plan_resolve_span and rm_plan_resolve_group replace the entries in
 * the span records and hit groups, rm_plan_clear_region empties the table for the next batch; with
 * span work per region a stable radix sort on the rank and rm_plan_gather_span group the records
 * by region, in ray order within each.
 *
 * Region table layout (4 * entries words): keys, first span records, span records, samples. */
#ifndef RAYMAP_KERNELS_DEVICE_PLAN_H
#define RAYMAP_KERNELS_DEVICE_PLAN_H

#include "../common/batch.h"
#include "../common/plan_abi.h"
#include "../common/ray.h"
#include "../common/region_walk.h"
#include "device.h"

/* Whether region `r` is planned: inside the rolling window, or any region of a growing map. */
RM_DEVICE_FN int rm_plan_in_window(rm_vec3i r, rm_plan_args a) {
  return a.rolling == 0u || (r.x >= a.window_lo.x && r.x <= a.window_hi.x && r.y >= a.window_lo.y &&
                             r.y <= a.window_hi.y && r.z >= a.window_lo.z && r.z <= a.window_hi.z);
}

/* Work-item 0: the status of a new plan (no cut, nothing counted). */
RM_DEVICE_FN void rm_plan_begin_status(rm_u32 id, RM_GLOBAL rm_u32* status) {
  rm_u32 w;
  if (id != 0u) {
    return;
  }
  for (w = 0u; w < RM_PLAN_STATUS_WORDS; ++w) {
    status[w] = 0u;
  }
  status[RM_PLAN_STATUS_CUT_RAY] = RM_PLAN_NONE;
}

/* Step 1, work-item r <= n: ray r's spans inside the window (0 for r == n, the scan's total),
 * and the regions it crosses. */
RM_DEVICE_FN void rm_plan_count_ray(rm_u32 r, rm_plan_args a, const RM_GLOBAL rm_prepared_ray* rays,
                                    RM_GLOBAL rm_u32* counts, RM_GLOBAL rm_u32* crossed) {
  rm_region_walk w;
  rm_region_span s;
  rm_u32 count = 0u;
  if (r > a.n) {
    return;
  }
  if (r < a.n && (rays[r].flags & RM_RAY_SKIP) != 0u) {
    crossed[r] = 0u; /* rejected by the device's preparation */
  } else if (r < a.n) {
    rm_region_walk_init(&w, rays[r], a.region_voxels);
    crossed[r] = rm_region_walk_regions(&w);
    while (rm_region_walk_next(&w, &s)) {
      count += rm_plan_in_window(s.region, a) ? 1u : 0u;
    }
  }
  counts[r] = count;
}

/* Step 2b, work-item r < n: the batch ends before the first ray that might not fit max_spans
 * span records, judged by the regions it crosses, as the host planner judges it (no region of
 * that ray or a later one is planned). */
RM_DEVICE_FN void rm_plan_cut_ray(rm_u32 r, rm_plan_args a, const RM_GLOBAL rm_u32* offsets,
                                  const RM_GLOBAL rm_u32* crossed,
                                  RM_ATOMIC_GLOBAL rm_u32* status) {
  if (r < a.n && offsets[r] + crossed[r] > a.max_spans) {
    (void)rm_atomic_min_u32(status + RM_PLAN_STATUS_CUT_RAY, r);
  }
}

/* The table entry of relative key `key`, inserted if new; NONE when the table is full. Linear
 * probing from a Fibonacci hash; an entry once claimed keeps its key for the batch, so a plain
 * read that sees the key is final. */
RM_DEVICE_FN rm_u32 rm_plan_table_insert(RM_ATOMIC_GLOBAL rm_u32* keys, rm_u32 key,
                                         rm_plan_args a) {
  rm_u32 h = (key * 0x9E3779B1u) >> a.table_shift;
  rm_u32 probes;
  for (probes = 0u; probes <= a.table_mask; ++probes) {
    rm_u32 seen = rm_load_u32(keys + h);
    if (seen == RM_PLAN_NONE) {
      seen = rm_atomic_cas_u32(keys + h, RM_PLAN_NONE, key);
      if (seen == RM_PLAN_NONE) {
        return h;
      }
    }
    if (seen == key) {
      return h;
    }
    h = (h + 1u) & a.table_mask;
  }
  return RM_PLAN_NONE;
}

/* Step 3, work-item r < n: writes ray r's span records and hit key (see the file comment). */
RM_DEVICE_FN void rm_plan_emit_ray(rm_u32 r, rm_plan_args a, const RM_GLOBAL rm_prepared_ray* rays,
                                   const RM_GLOBAL rm_u32* offsets, RM_GLOBAL rm_span_record* spans,
                                   RM_ATOMIC_GLOBAL rm_u32* table, RM_GLOBAL rm_u32* hit_keys,
                                   RM_GLOBAL rm_u32* hit_rays, RM_ATOMIC_GLOBAL rm_u32* status) {
  rm_u32 entries = a.table_mask + 1u;
  rm_prepared_ray ray;
  rm_region_walk w;
  rm_region_span s;
  rm_u32 at;
  rm_u32 outside = 0u;
  rm_u32 faults = 0u;
  rm_u32 sample_flag;
  rm_u32 sample_entry = RM_PLAN_NONE;
  if (r >= a.n) {
    return;
  }
  hit_rays[r] = r;
  hit_keys[r] = RM_PLAN_NONE;
  if (r >= rm_load_u32(status + RM_PLAN_STATUS_CUT_RAY)) {
    return; /* the batch ends before it */
  }
  at = offsets[r];
  ray = rays[r];
  if ((ray.flags & RM_RAY_SKIP) != 0u) {
    return; /* rejected by the device's preparation: no spans, no sample */
  }
  rm_region_walk_init(&w, ray, a.region_voxels);
  sample_flag = rm_region_walk_sample_flag(&w);
  while (rm_region_walk_next(&w, &s)) {
    rm_u32 key;
    rm_u32 entry = RM_PLAN_NONE;
    rm_span_record record;
    if (!rm_plan_in_window(s.region, a)) {
      outside += 1u;
      continue;
    }
    key = rm_plan_region_key(s.region, a.key_origin);
    if (key == RM_PLAN_NONE) {
      faults |= RM_PLAN_FAULT_KEY_RANGE;
    } else {
      entry = rm_plan_table_insert(table, key, a);
      faults |= entry == RM_PLAN_NONE ? RM_PLAN_FAULT_TABLE_FULL : 0u;
    }
    record.ray = r;
    record.slot = entry; /* the table entry until the resolve phase */
    record.flags = s.flags;
    record.t0 = s.t0;
    record.t1 = s.t1;
    record.box_lo = s.box_lo;
    spans[at] = record;
    if (entry != RM_PLAN_NONE) {
      (void)rm_atomic_min_u32(table + entries + entry, at);
      (void)rm_atomic_add_u32(table + 2u * entries + entry, 1u);
      if ((s.flags & sample_flag) != 0u) {
        sample_entry = entry;
      }
    }
    at += 1u;
  }
  if (outside != 0u) {
    (void)rm_atomic_add_u32(status + RM_PLAN_STATUS_OUTSIDE, outside);
  }
  if (faults != 0u) {
    (void)rm_atomic_or_u32(status + RM_PLAN_STATUS_FAULT, faults);
  }
  if ((ray.flags & RM_RAY_END_HIT) != 0u && sample_entry != RM_PLAN_NONE) {
    rm_vec3i region;
    rm_u32 index = rm_region_walk_sample_cell(&w, &region);
    hit_keys[r] = sample_entry * a.voxels_per_region + index;
    (void)rm_atomic_add_u32(table + 3u * entries + sample_entry, 1u);
    (void)rm_atomic_add_u32(status + RM_PLAN_STATUS_HITS, 1u);
  }
}

/* Step 4, work-item i <= n: 1 where sorted key i starts a new voxel (0 for i == n). */
RM_DEVICE_FN void rm_plan_group_head(rm_u32 i, rm_u32 n, const RM_GLOBAL rm_u32* keys,
                                     RM_GLOBAL rm_u32* heads) {
  if (i > n) {
    return;
  }
  heads[i] = (i < n && keys[i] != RM_PLAN_NONE && (i == 0u || keys[i] != keys[i - 1u])) ? 1u : 0u;
}

/* Step 4, work-item i < n: copies sorted ray i into the hit-ray list and, where a voxel's samples
 * start, writes its hit group (number group_index[i]). */
RM_DEVICE_FN void rm_plan_group_build_item(rm_u32 i, rm_plan_args a, const RM_GLOBAL rm_u32* keys,
                                           const RM_GLOBAL rm_u32* rays,
                                           const RM_GLOBAL rm_u32* heads,
                                           const RM_GLOBAL rm_u32* group_index,
                                           RM_GLOBAL rm_hit_group* groups,
                                           RM_GLOBAL rm_u32* hit_rays) {
  rm_u32 key;
  rm_u32 end;
  rm_hit_group group;
  if (i >= a.n) {
    return;
  }
  hit_rays[i] = rays[i];
  if (heads[i] == 0u) {
    return;
  }
  key = keys[i];
  for (end = i + 1u; end < a.n && keys[end] == key; ++end) {
  }
  group.slot = key / a.voxels_per_region; /* the table entry until the resolve phase */
  group.index = key % a.voxels_per_region;
  group.first = i;
  group.count = end - i;
  groups[group_index[i]] = group;
}

/* Step 5, work-item e < table entries: lists entry e's region for the host if it holds one. */
RM_DEVICE_FN void rm_plan_compact_entry(rm_u32 e, rm_plan_args a, const RM_GLOBAL rm_u32* table,
                                        const RM_GLOBAL rm_span_record* spans,
                                        RM_GLOBAL rm_plan_region* regions,
                                        RM_ATOMIC_GLOBAL rm_u32* status) {
  rm_u32 entries = a.table_mask + 1u;
  rm_u32 k;
  rm_plan_region region;
  if (e >= entries || table[e] == RM_PLAN_NONE) {
    return;
  }
  k = rm_atomic_add_u32(status + RM_PLAN_STATUS_REGIONS, 1u);
  if (k >= a.region_cap) {
    return; /* the count tells the host that the list is short */
  }
  region.key = table[e];
  region.entry = e;
  region.first_span = table[entries + e];
  region.first_ray = spans[region.first_span].ray;
  region.spans = table[2u * entries + e];
  region.hits = table[3u * entries + e];
  regions[k] = region;
}

/* Step 5, work-item 0: the plan's span records (those of the rays before the cut) and groups. */
RM_DEVICE_FN void rm_plan_finish_status(rm_u32 id, rm_plan_args a, const RM_GLOBAL rm_u32* offsets,
                                        const RM_GLOBAL rm_u32* group_index,
                                        RM_GLOBAL rm_u32* status) {
  rm_u32 cut;
  if (id != 0u) {
    return;
  }
  cut = status[RM_PLAN_STATUS_CUT_RAY];
  cut = cut < a.n ? cut : a.n;
  status[RM_PLAN_STATUS_SPANS] = offsets[cut];
  status[RM_PLAN_STATUS_GROUPS] = group_index[a.n];
}

/* Resolve, work-item k < regions: entry_map[entry] = slot, entry_map[entries + entry] = rank. */
RM_DEVICE_FN void rm_plan_resolve_region(rm_u32 k, rm_plan_args a,
                                         const RM_GLOBAL rm_plan_region* regions,
                                         const RM_GLOBAL rm_plan_resolution* resolutions,
                                         RM_GLOBAL rm_u32* entry_map) {
  rm_u32 entry;
  if (k >= a.n) {
    return;
  }
  entry = regions[k].entry;
  entry_map[entry] = resolutions[k].slot;
  entry_map[a.table_mask + 1u + entry] = resolutions[k].rank;
}

/* Resolve, work-item i < spans: span record i's slot; with `with_rank`, its run's rank and its
 * index as the (key, value) pair the grouping sort orders. */
RM_DEVICE_FN void rm_plan_resolve_span(rm_u32 i, rm_plan_args a, int with_rank,
                                       RM_GLOBAL rm_span_record* spans,
                                       const RM_GLOBAL rm_u32* entry_map,
                                       RM_GLOBAL rm_u32* rank_keys, RM_GLOBAL rm_u32* span_index) {
  rm_u32 entry;
  if (i >= a.n) {
    return;
  }
  entry = spans[i].slot;
  spans[i].slot = entry_map[entry];
  if (with_rank) {
    rank_keys[i] = entry_map[a.table_mask + 1u + entry];
    span_index[i] = i;
  }
}

/* Resolve, work-item g < groups: hit group g's slot. */
RM_DEVICE_FN void rm_plan_resolve_group(rm_u32 g, rm_plan_args a, RM_GLOBAL rm_hit_group* groups,
                                        const RM_GLOBAL rm_u32* entry_map) {
  if (g < a.n) {
    groups[g].slot = entry_map[groups[g].slot];
  }
}

/* Span work per region, work-item j < spans: the j-th record in region order. */
RM_DEVICE_FN void rm_plan_gather_span(rm_u32 j, rm_plan_args a,
                                      const RM_GLOBAL rm_span_record* spans,
                                      const RM_GLOBAL rm_u32* order,
                                      RM_GLOBAL rm_span_record* region_spans) {
  if (j < a.n) {
    region_spans[j] = spans[order[j]];
  }
}

/* Empties table entry `e`. */
RM_DEVICE_FN void rm_plan_clear_entry(rm_u32 e, rm_u32 entries, RM_GLOBAL rm_u32* table) {
  table[e] = RM_PLAN_NONE;
  table[entries + e] = RM_PLAN_NONE;
  table[2u * entries + e] = 0u;
  table[3u * entries + e] = 0u;
}

#endif /* RAYMAP_KERNELS_DEVICE_PLAN_H */
