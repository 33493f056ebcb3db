/* SPDX-License-Identifier: BSD-3-Clause */
/* Height-map generation: the per-column surface search and the flood-fill reference rule, shared
 * by the CPU generator, OpenCL and CUDA (one work-item per column).
 *
 * Frames and units: world frame, z up, metres. A height-map cell is exactly one voxel column of
 * the map. Cells follow grid_map's conventions: cell (i, j) with i along -x and j along -y, so
 * (0, 0) is the +x/+y corner, and layers are stored column-major, index i + j * cells_x.
 *
 * The column search, for a column and a reference height `ref` (metres):
 *  - the search range is the voxels whose centres lie in [ref - floor_depth, ref + ceiling_height],
 *    clipped to the box the host mapped (the region table);
 *  - a *surface* candidate is the top voxel of a run of occupied voxels; its height is the voxel
 *    mean's z when the mean layer is present and has samples, else the voxel centre. A run with
 *    observed free space directly below it and unobserved space directly above it was seen only
 *    from below (a ceiling, the underside of an overhang): it limits the clearance of what is
 *    below it but is no candidate itself;
 *  - a *virtual surface* candidate (only with RM_HM_FLAG_VIRTUAL) is, in each gap between runs of
 *    occupied voxels, the lowest free voxel within the search range whose voxel below is
 *    unobserved: free space seen over space
 *    never seen, as at a ditch or a drop-off seen from above. Its height is the voxel's bottom face
 *    (the highest the hidden ground can be). Virtual candidates above ref + one voxel are ignored:
 *    those are shadows behind obstacles, which stay unknown, not negative obstacles;
 *  - a candidate's clearance is the distance from its height up to the bottom face of the next
 *    occupied voxel above it (+inf when none up to the top of the box); it qualifies when the
 *    clearance is at least min_clearance (unobserved space counts as clear);
 *  - the qualifying candidate nearest to ref wins; on equal distance a surface beats a virtual
 *    surface and the lower beats the higher.
 * Without a candidate the cell is *vacant* when the lowest voxel of the search range is observed
 * free (observed empty space reaches the floor limit: a drop deeper than the search), and
 * *unknown* otherwise. Elevation and clearance are NaN for vacant and unknown cells.
 *
 * Modes: planar uses the fixed reference for every cell. Flood fill starts at the seed cell with
 * the fixed reference and proceeds ring by ring (Chebyshev distance from the seed); a cell of ring
 * k takes as its reference the elevation of its parent in ring k - 1 (the neighbour one step
 * toward the seed), else of the parent's two side neighbours in ring k - 1 that have one, else
 * the parent's own reference. So stairs and ramps are followed outward from the robot, and all
 * cells of a ring are independent: one launch per ring on a device, the same order on the CPU,
 * the same result.
 *
 * Normals (RM_HM_FLAG_NORMALS, maps with an NDT layer): a surface cell's normal is the normal of
 * the Gaussian of the voxel its elevation comes from (ndt_normal.h: unit, world frame, pointing
 * up, NaN unless the Gaussian is valid). Virtual, vacant and unknown cells have NaN normals. */
#ifndef RAYMAP_KERNELS_COMMON_HEIGHTMAP_H
#define RAYMAP_KERNELS_COMMON_HEIGHTMAP_H

#include "key_math.h"
#include "ndt_normal.h"
#include "occupancy.h"
#include "portable.h"
#include "voxel_mean.h"

/* Cell kinds (the `kind` layer). Stable values: they are published and written to files. */
#define RM_HM_UNKNOWN 0u
#define RM_HM_SURFACE 1u
#define RM_HM_VIRTUAL 2u
#define RM_HM_VACANT 3u

/* Parameter flags. */
#define RM_HM_FLAG_VIRTUAL 1  /* look for virtual surfaces */
#define RM_HM_FLAG_MEAN 2     /* surface heights from the voxel mean (needs RM_HM_FLAG_SAMPLES) */
#define RM_HM_FLAG_FILL 4     /* flood-fill mode (else planar) */
#define RM_HM_FLAG_SAMPLES 8  /* the mean layer is present: read sample counts from it */
#define RM_HM_FLAG_NORMALS 16 /* the NDT layer is present: write the normal layers */

/* Region table entry of a region the map does not hold (all its voxels are unobserved). */
#define RM_HM_NO_REGION 0xFFFFFFFFu
/* Voxel index of a candidate without a voxel of its own (virtual surfaces, no candidate). */
#define RM_HM_NO_VOXEL 0xFFFFFFFFu

/* Everything a column search needs; a plain struct passed by value to kernels. */
typedef struct rm_heightmap_params {
  rm_i32 cells_x;   /* cells along x (rows of the grid_map matrix) */
  rm_i32 cells_y;   /* cells along y (columns) */
  rm_i32 voxel_x0;  /* global voxel x of cell i = 0 (cell i covers voxel x0 - i) */
  rm_i32 voxel_y0;  /* global voxel y of cell j = 0 */
  rm_i32 region_x0; /* region coordinate of the region table's first entry */
  rm_i32 region_y0;
  rm_i32 region_z0;
  rm_i32 regions_x; /* region table size */
  rm_i32 regions_y;
  rm_i32 regions_z;
  rm_i32 region_voxels;
  rm_i32 box_z_min; /* lowest global voxel z of the box (the search never goes below) */
  rm_i32 box_z_max; /* highest global voxel z of the box */
  rm_i32 seed_i;    /* flood-fill seed cell */
  rm_i32 seed_j;
  rm_i32 flags;              /* RM_HM_FLAG_* */
  rm_i32 region_shift;       /* log2(region_voxels) when it is a power of two, else -1 */
  float resolution;          /* voxel edge, metres */
  float inverse_resolution;  /* 1 / resolution: search limits are multiplied by it (a float
                              * product is correctly rounded on every device; a quotient is not) */
  float reference_z;         /* planar reference / fill seed reference, metres */
  float floor_depth;         /* metres searched below the reference */
  float ceiling_height;      /* metres searched above the reference */
  float min_clearance;       /* metres */
  float occupied_threshold;  /* log-odds: occupied when value >= threshold */
  rm_u32 normal_min_samples; /* samples an NDT Gaussian needs for a normal (RM_HM_FLAG_NORMALS) */
} rm_heightmap_params;

/* The result of one column search. */
typedef struct rm_heightmap_cell {
  float elevation; /* metres, world z; NaN unless surface or virtual */
  float clearance; /* metres; +inf when open above; NaN unless surface or virtual */
  rm_u32 kind;     /* RM_HM_* */
  rm_u32 samples;  /* samples in the surface voxel (voxel mean count); 0 otherwise */
  rm_u32 voxel;    /* the surface voxel in the uploaded layers (slot * region voxels + local
                    * index), or RM_HM_NO_VOXEL */
} rm_heightmap_cell;

/* Region coordinate of a voxel coordinate: a shift when the region size is a power of two (the
 * default 32), else a floor division. Integer division costs tens of cycles, and every column
 * needs three. */
RAYMAP_FN rm_i32 rm_hm_region_of(rm_heightmap_params p, rm_i32 v) {
  if (p.region_shift >= 0) {
    /* floor(v / 2^s) without shifting a negative number: ~v = -v - 1 >= 0 for v < 0. */
    return v >= 0 ? (v >> p.region_shift) : ~((~v) >> p.region_shift);
  }
  return rm_floor_div(v, p.region_voxels);
}

/* Voxel states as the search sees them. */
#define RM_HM_STATE_UNOBSERVED 0
#define RM_HM_STATE_FREE 1
#define RM_HM_STATE_OCCUPIED 2

/* Column masks: the search reads voxel states as bits, 32 voxels of one column of one region per
 * word pair (bit b = voxel z = region base + 32 w + b), built once per generation from the
 * occupancy layer. A column then costs a few bit operations per 32 voxels instead of one strided
 * memory read per voxel. */
typedef struct rm_hm_mask {
  rm_u32 occupied; /* observed and at or above the threshold */
  rm_u32 observed;
} rm_hm_mask;

/* Mask words per region column. */
RAYMAP_FN rm_i32 rm_hm_mask_words(rm_i32 region_voxels) { return (region_voxels + 31) / 32; }

/* The mask bits of one voxel's occupancy value, 0 or 1 (branch-free, so host loops over a plane
 * of voxels vectorise). */
RAYMAP_FN rm_u32 rm_hm_observed_bit(float value) { return RM_U32(value != RM_OCC_UNOBSERVED); }
RAYMAP_FN rm_u32 rm_hm_occupied_bit(float value, float threshold) {
  return RM_U32(value >= threshold) & RM_U32(value != RM_OCC_UNOBSERVED);
}

/* Folds one voxel's occupancy value into its mask word as bit b (voxel z = word base + b). */
RAYMAP_FN void rm_hm_mask_add(rm_hm_mask* m, rm_i32 b, float value, float threshold) {
  m->observed |= rm_hm_observed_bit(value) << b;
  m->occupied |= rm_hm_occupied_bit(value, threshold) << b;
}

/* Index of the lowest set bit of x != 0. */
RAYMAP_FN rm_i32 rm_hm_lowest_bit(rm_u32 x) {
#if defined(__OPENCL_C_VERSION__)
  return 31 - RM_I32(clz(x & (0u - x)));
#elif defined(__CUDA_ARCH__)
  return __ffs(RM_I32(x)) - 1;
#else
  return __builtin_ctz(x);
#endif
}

/* Where the column search reads the map. `table` maps each region of the box (x fastest) to a
 * region index r (or RM_HM_NO_REGION); `masks` holds r's column masks at
 * (r * region_voxels^2 + column) * words + w; `region_slots[r]` is r's slot in `mean` (the
 * voxel-mean layer, indexed slot * voxels-per-region + local index; read only with
 * RM_HM_FLAG_MEAN); `ndt` is the NDT layer, indexed likewise (read only with RM_HM_FLAG_NORMALS).
 */
typedef struct rm_hm_sources {
  RAYMAP_GLOBAL const rm_u32* table;
  RAYMAP_GLOBAL const rm_u32* region_slots;
  RAYMAP_GLOBAL const rm_hm_mask* masks;
  RAYMAP_GLOBAL const rm_voxel_mean* mean;
  RAYMAP_GLOBAL const rm_ndt_voxel* ndt;
} rm_hm_sources;

/* A candidate waiting for the next occupied voxel above it, which fixes its clearance. */
typedef struct rm_hm_candidate {
  float height;
  rm_u32 kind; /* RM_HM_SURFACE, RM_HM_VIRTUAL, or RM_HM_UNKNOWN for none */
  rm_u32 samples;
  rm_u32 voxel; /* as rm_heightmap_cell.voxel */
} rm_hm_candidate;

RAYMAP_FN rm_hm_candidate rm_hm_no_candidate(void) {
  rm_hm_candidate c;
  c.height = 0.0f;
  c.kind = RM_HM_UNKNOWN;
  c.samples = 0u;
  c.voxel = RM_HM_NO_VOXEL;
  return c;
}

/* Offers a resolved candidate to the best-so-far. Candidates arrive bottom-up. */
RAYMAP_FN void rm_hm_offer(rm_heightmap_cell* best, float* best_distance, rm_hm_candidate c,
                           float clearance, float reference, float min_clearance) {
  if (c.kind == RM_HM_UNKNOWN || !(clearance >= min_clearance)) {
    return;
  }
  float distance = RM_FABSF(c.height - reference);
  int better = distance < *best_distance;
  if (!better && distance == *best_distance) {
    /* Equal distance: a surface beats a virtual surface; otherwise the lower (earlier) stays. */
    better = c.kind == RM_HM_SURFACE && best->kind == RM_HM_VIRTUAL;
  }
  if (better) {
    *best_distance = distance;
    best->elevation = c.height;
    best->clearance = clearance;
    best->kind = c.kind;
    best->samples = c.samples;
    best->voxel = c.voxel;
  }
}

/* State of bit b of a mask word. */
RAYMAP_FN rm_i32 rm_hm_bit_state(rm_hm_mask m, rm_i32 b) {
  if (((m.occupied >> b) & 1u) != 0u) {
    return RM_HM_STATE_OCCUPIED;
  }
  return ((m.observed >> b) & 1u) != 0u ? RM_HM_STATE_FREE : RM_HM_STATE_UNOBSERVED;
}

/* Searches the column of global voxel (vx, vy) around `reference` (metres). */
RAYMAP_FN rm_heightmap_cell rm_heightmap_column(rm_heightmap_params p, rm_hm_sources src, rm_i32 vx,
                                                rm_i32 vy, float reference) {
  rm_heightmap_cell best;
  best.elevation = RM_F32(NAN);
  best.clearance = RM_F32(NAN);
  best.kind = RM_HM_UNKNOWN;
  best.samples = 0u;
  best.voxel = RM_HM_NO_VOXEL;
  float best_distance = RM_INF;

  const float res = p.resolution;
  const rm_i32 n = p.region_voxels;
  const rm_i32 words = rm_hm_mask_words(n);
  const rm_u32 voxels_per_region = RM_U32(n * n * n);
  const rm_u32 plane = RM_U32(n * n);
  /* Voxels whose centre lies in [reference - floor, reference + ceiling]. */
  rm_i32 z_lo = rm_floor_i32((reference - p.floor_depth) * p.inverse_resolution + 0.5f);
  rm_i32 z_hi = rm_floor_i32((reference + p.ceiling_height) * p.inverse_resolution - 0.5f);
  z_lo = z_lo < p.box_z_min ? p.box_z_min : z_lo;
  z_hi = z_hi > p.box_z_max ? p.box_z_max : z_hi;
  if (z_lo > z_hi) {
    return best;
  }
  const rm_i32 rx = rm_hm_region_of(p, vx);
  const rm_i32 ry = rm_hm_region_of(p, vy);
  const rm_u32 column = RM_U32((vx - rx * n) + n * (vy - ry * n));
  const int virtual_on = (p.flags & RM_HM_FLAG_VIRTUAL) != 0;
  const int samples_on = (p.flags & RM_HM_FLAG_SAMPLES) != 0;
  const int mean_on = samples_on && (p.flags & RM_HM_FLAG_MEAN) != 0;
  const float virtual_limit = reference + res;

  rm_hm_candidate real = rm_hm_no_candidate();   /* top of the occupied run below this gap */
  rm_hm_candidate hidden = rm_hm_no_candidate(); /* virtual candidate in this gap */
  rm_i32 previous = RM_HM_STATE_UNOBSERVED;      /* state of the voxel below the current one */
  rm_i32 lowest_state = RM_HM_STATE_UNOBSERVED;  /* state of voxel z_lo */
  int gap_has_virtual = 0;
  int check_above = 0;    /* `real` is an underside if the voxel above it (next word) is unseen */
  int run_free_below = 0; /* the run of occupied voxels ending at `real` has free space below */
  int done = 0;

  /* Walk mask word by mask word from the voxel below the box up to its top, visiting only events:
   * occupied voxels and, for virtual surfaces, free voxels over unobserved ones. The walk starts
   * below the box rather than at z_lo so that a run of occupied voxels is judged by the voxel
   * below it wherever the search range begins, and clearances look above the search range. Stop
   * early once a resolved candidate at or above the reference is held: every later candidate is
   * higher, so farther away. */
  /* The column's entries in the region table (one per region layer), when it is in the box. */
  const rm_i32 tx = rx - p.region_x0;
  const rm_i32 ty = ry - p.region_y0;
  const int column_in_box = tx >= 0 && ty >= 0 && tx < p.regions_x && ty < p.regions_y;
  const rm_u32 table_column = RM_U32(column_in_box ? tx + p.regions_x * ty : 0);
  const rm_u32 table_layer = RM_U32(p.regions_x * p.regions_y);
  /* Region layer and mask word of the first voxel, then advanced word by word (no division in
   * the loop). */
  rm_i32 z = p.box_z_min - 1;
  rm_i32 rz = rm_hm_region_of(p, z);
  rm_i32 w = (z - rz * n) / 32;
  while (z <= p.box_z_max && !done) {
    const rm_i32 word_z = rz * n + w * 32; /* voxel of bit 0 */
    const rm_i32 word_bits = (n - w * 32) < 32 ? (n - w * 32) : 32;
    const rm_i32 z_end =
        (word_z + word_bits - 1) < p.box_z_max ? (word_z + word_bits - 1) : p.box_z_max;
    const rm_i32 tz = rz - p.region_z0;
    const rm_u32 region = (column_in_box && tz >= 0 && tz < p.regions_z)
                              ? src.table[table_column + table_layer * RM_U32(tz)]
                              : RM_HM_NO_REGION;
    rm_hm_mask m;
    m.occupied = 0u;
    m.observed = 0u;
    if (region != RM_HM_NO_REGION) {
      m = src.masks[(region * plane + column) * RM_U32(words) + RM_U32(w)];
    }
    if (check_above) {
      check_above = 0;
      if (rm_hm_bit_state(m, z - word_z) == RM_HM_STATE_UNOBSERVED) {
        real = rm_hm_no_candidate();
      }
    }
    if (m.occupied == 0u &&
        (m.observed == 0u || (m.observed == 0xFFFFFFFFu && previous == RM_HM_STATE_FREE))) {
      /* All unobserved, or free continuing a free run: no event (the common case above the
       * ground and in regions the map does not hold). */
      previous = m.observed == 0u ? RM_HM_STATE_UNOBSERVED : RM_HM_STATE_FREE;
      if (z_lo >= z && z_lo <= z_end) {
        lowest_state = previous;
      }
      z = z_end + 1;
      if (++w == words) {
        w = 0;
        ++rz;
      }
      continue;
    }
    const rm_i32 b0 = z - word_z;
    const rm_i32 b1 = z_end - word_z;
    const rm_u32 range = (b1 == 31 ? 0xFFFFFFFFu : ((1u << (b1 + 1)) - 1u)) & ~((1u << b0) - 1u);
    if (z_lo >= z && z_lo <= z_end) {
      lowest_state = rm_hm_bit_state(m, z_lo - word_z);
    }
    rm_u32 events = m.occupied & range;
    if (virtual_on) {
      /* Free voxels whose voxel below is unobserved (bit b0's "below" is `previous`). */
      rm_u32 below_unobserved = (~m.observed) << 1;
      below_unobserved =
          (below_unobserved & ~(1u << b0)) | (previous == RM_HM_STATE_UNOBSERVED ? (1u << b0) : 0u);
      events |= m.observed & ~m.occupied & below_unobserved & range;
    }
    while (events != 0u && !done) {
      const rm_i32 b = rm_hm_lowest_bit(events);
      events &= events - 1u;
      const rm_i32 ze = word_z + b;
      if (((m.occupied >> b) & 1u) != 0u) {
        const rm_i32 below = b == b0 ? previous : rm_hm_bit_state(m, b - 1);
        if (below == RM_HM_STATE_OCCUPIED) {
          /* Inside a run of occupied voxels: only the run's top can be a surface. */
          real = rm_hm_no_candidate();
        } else {
          /* A new run: the gap below ends here, so resolve its candidates. */
          const float ceiling_face = RM_F32(ze) * res;
          rm_hm_offer(&best, &best_distance, real, ceiling_face - real.height, reference,
                      p.min_clearance);
          rm_hm_offer(&best, &best_distance, hidden, ceiling_face - hidden.height, reference,
                      p.min_clearance);
          real = rm_hm_no_candidate();
          hidden = rm_hm_no_candidate();
          gap_has_virtual = 0;
          run_free_below = below == RM_HM_STATE_FREE;
          if (best.kind != RM_HM_UNKNOWN && best.elevation >= reference) {
            done = 1;
          }
        }
        if (!done && ze > z_hi) {
          done = 1; /* nothing above the search range can become a candidate */
        } else if (!done && ze >= z_lo) {
          /* A run with observed free space directly below it and unobserved space directly
           * above it was seen only from below (a ceiling, the underside of an overhang): it
           * bounds the clearance below it but is no ground to stand on. */
          int underside = 0;
          if (run_free_below) {
            if (ze < z_end) {
              underside = rm_hm_bit_state(m, b + 1) == RM_HM_STATE_UNOBSERVED;
            } else {
              check_above = 1; /* decided by the next word's first voxel */
            }
          }
          real.kind = underside ? RM_HM_UNKNOWN : RM_HM_SURFACE;
          real.height = (RM_F32(ze) + 0.5f) * res;
          real.voxel =
              src.region_slots[region] * voxels_per_region + column + RM_U32(ze - rz * n) * plane;
          if (samples_on) {
            const rm_voxel_mean mv = src.mean[real.voxel];
            if (mean_on && mv.count > 0u) {
              real.height = (RM_F32(ze) + rm_mean_decode(mv.packed, mv.count).z) * res;
            }
            real.samples = mv.count;
          }
        }
      } else if (ze >= z_lo && ze <= z_hi) {
        /* The lowest free voxel over unobserved space in this gap. */
        const float height = RM_F32(ze) * res;
        if (!gap_has_virtual && height <= virtual_limit) {
          hidden.kind = RM_HM_VIRTUAL;
          hidden.height = height;
          hidden.samples = 0u;
          hidden.voxel = RM_HM_NO_VOXEL;
        }
        gap_has_virtual = 1;
      }
    }
    previous = rm_hm_bit_state(m, b1);
    z = z_end + 1;
    if (++w == words) {
      w = 0;
      ++rz;
    }
  }
  if (!done) {
    if (check_above) {
      real = rm_hm_no_candidate(); /* the voxel above lies outside the box: unobserved */
    }
    /* Open above: nothing occupied up to the top of the box. */
    rm_hm_offer(&best, &best_distance, real, RM_INF, reference, p.min_clearance);
    rm_hm_offer(&best, &best_distance, hidden, RM_INF, reference, p.min_clearance);
  }
  if (best.kind == RM_HM_UNKNOWN && lowest_state == RM_HM_STATE_FREE) {
    best.kind = RM_HM_VACANT;
  }
  return best;
}

/* Builds the masks of one region column: work-item g of region_count * region_voxels^2 (columns
 * fastest, so neighbouring items read neighbouring voxels). `occupancy` is indexed like `mean`. */
RAYMAP_FN void rm_hm_mask_item(rm_heightmap_params p, RAYMAP_GLOBAL const rm_u32* region_slots,
                               RAYMAP_GLOBAL const float* occupancy,
                               RAYMAP_GLOBAL rm_hm_mask* masks, rm_u32 region_count, rm_u32 g) {
  const rm_i32 n = p.region_voxels;
  const rm_u32 plane = RM_U32(n * n);
  if (g >= region_count * plane) {
    return;
  }
  const rm_u32 region = g / plane;
  const rm_u32 column = g - region * plane;
  const rm_i32 words = rm_hm_mask_words(n);
  RAYMAP_GLOBAL const float* voxels = occupancy + region_slots[region] * RM_U32(n * n * n) + column;
  for (rm_i32 w = 0; w < words; ++w) {
    rm_hm_mask m;
    m.occupied = 0u;
    m.observed = 0u;
    const rm_i32 bits = (n - w * 32) < 32 ? (n - w * 32) : 32;
    for (rm_i32 b = 0; b < bits; ++b) {
      rm_hm_mask_add(&m, b, voxels[RM_U32(w * 32 + b) * plane], p.occupied_threshold);
    }
    masks[g * RM_U32(words) + RM_U32(w)] = m;
  }
}

/* Global voxel column of cell (i, j). */
RAYMAP_FN rm_i32 rm_hm_voxel_x(rm_heightmap_params p, rm_i32 i) { return p.voxel_x0 - i; }
RAYMAP_FN rm_i32 rm_hm_voxel_y(rm_heightmap_params p, rm_i32 j) { return p.voxel_y0 - j; }

/* Number of flood-fill rings: the largest Chebyshev distance from the seed to a cell. */
RAYMAP_FN rm_i32 rm_hm_ring_count(rm_heightmap_params p) {
  rm_i32 k = p.seed_i;
  k = (p.cells_x - 1 - p.seed_i) > k ? (p.cells_x - 1 - p.seed_i) : k;
  k = p.seed_j > k ? p.seed_j : k;
  k = (p.cells_y - 1 - p.seed_j) > k ? (p.cells_y - 1 - p.seed_j) : k;
  return k + 1;
}

/* Work-items of ring k: 1 for the seed, else the 8k cells of the square's perimeter. */
RAYMAP_FN rm_u32 rm_hm_ring_size(rm_i32 k) { return k == 0 ? 1u : RM_U32(8 * k); }

/* Cell offset (di, dj) from the seed of item g of ring k >= 1: the four sides in turn, each 2k
 * cells (top side dj = -k, then di = +k, then dj = +k, then di = -k). */
RAYMAP_FN void rm_hm_ring_cell(rm_i32 k, rm_i32 g, rm_i32* di, rm_i32* dj) {
  const rm_i32 side = g / (2 * k);
  const rm_i32 step = g - side * 2 * k;
  if (side == 0) {
    *di = -k + step;
    *dj = -k;
  } else if (side == 1) {
    *di = k;
    *dj = -k + step;
  } else if (side == 2) {
    *di = k - step;
    *dj = k;
  } else {
    *di = -k;
    *dj = k - step;
  }
}

RAYMAP_FN int rm_hm_has_height(rm_u32 kind) {
  return kind == RM_HM_SURFACE || kind == RM_HM_VIRTUAL;
}

/* Reference height of fill cell (i, j) at offset (di, dj) from the seed, ring k >= 1, from the
 * results of ring k - 1 (`elevation`, `kind`, `reference`: column-major layers). */
RAYMAP_FN float rm_hm_fill_reference(rm_heightmap_params p, RAYMAP_GLOBAL const float* elevation,
                                     RAYMAP_GLOBAL const rm_u32* kind,
                                     RAYMAP_GLOBAL const float* reference, rm_i32 i, rm_i32 j,
                                     rm_i32 di, rm_i32 dj, rm_i32 k) {
  /* The parent steps one cell toward the seed on each axis at the ring's distance. */
  const rm_i32 pi_ = i - (rm_abs_i32(di) == k ? rm_sign_i32(di) : 0);
  const rm_i32 pj = j - (rm_abs_i32(dj) == k ? rm_sign_i32(dj) : 0);
  const rm_i32 parent = pi_ + pj * p.cells_x;
  if (rm_hm_has_height(kind[parent])) {
    return elevation[parent];
  }
  /* The parent's neighbours along the ring's side, if they lie in ring k - 1 and in the grid. */
  const int along_i = rm_abs_i32(dj) == k && rm_abs_i32(di) != k; /* side runs along i */
  const int along_j = rm_abs_i32(di) == k && rm_abs_i32(dj) != k;
  if (along_i || along_j) {
    for (rm_i32 s = -1; s <= 1; s += 2) {
      const rm_i32 ni = pi_ + (along_i ? s : 0);
      const rm_i32 nj = pj + (along_j ? s : 0);
      const rm_i32 ndi = ni - p.seed_i;
      const rm_i32 ndj = nj - p.seed_j;
      const rm_i32 ring = rm_abs_i32(ndi) > rm_abs_i32(ndj) ? rm_abs_i32(ndi) : rm_abs_i32(ndj);
      if (ni >= 0 && nj >= 0 && ni < p.cells_x && nj < p.cells_y && ring == k - 1) {
        const rm_i32 n = ni + nj * p.cells_x;
        if (rm_hm_has_height(kind[n])) {
          return elevation[n];
        }
      }
    }
  }
  return reference[parent];
}

/* The output layers of a generation (column-major, cells_x * cells_y each). `reference` holds
 * the reference each cell was searched around (flood fill reads its parents' values). The normal
 * layers are written only with RM_HM_FLAG_NORMALS. */
typedef struct rm_hm_layers {
  RAYMAP_GLOBAL float* elevation;
  RAYMAP_GLOBAL float* clearance;
  RAYMAP_GLOBAL rm_u32* kind;
  RAYMAP_GLOBAL rm_u32* samples;
  RAYMAP_GLOBAL float* reference;
  RAYMAP_GLOBAL float* normal_x;
  RAYMAP_GLOBAL float* normal_y;
  RAYMAP_GLOBAL float* normal_z;
} rm_hm_layers;

RAYMAP_FN void rm_hm_store(rm_heightmap_params p, rm_hm_sources src, rm_hm_layers out, rm_i32 index,
                           rm_heightmap_cell c, float reference) {
  out.elevation[index] = c.elevation;
  out.clearance[index] = c.clearance;
  out.kind[index] = c.kind;
  out.samples[index] = c.samples;
  out.reference[index] = reference;
  if ((p.flags & RM_HM_FLAG_NORMALS) != 0) {
    /* Once per cell, for the winning candidate only: the eigen-solve costs more than the search's
     * bit operations. */
    rm_vec3f n;
    n.x = RM_F32(NAN);
    n.y = n.x;
    n.z = n.x;
    if (c.kind == RM_HM_SURFACE && c.voxel != RM_HM_NO_VOXEL) {
      const rm_ndt_voxel g = src.ndt[c.voxel];
      n = rm_ndt_normal(g.s, g.count, p.normal_min_samples);
    }
    out.normal_x[index] = n.x;
    out.normal_y[index] = n.y;
    out.normal_z[index] = n.z;
  }
}

/* Planar mode, work-item g of cells_x * cells_y (x fastest, so neighbouring items read
 * neighbouring voxels). */
RAYMAP_FN void rm_hm_planar_item(rm_heightmap_params p, rm_hm_sources src, rm_hm_layers out,
                                 rm_u32 g) {
  if (g >= RM_U32(p.cells_x * p.cells_y)) {
    return;
  }
  const rm_i32 i = RM_I32(g % RM_U32(p.cells_x));
  const rm_i32 j = RM_I32(g / RM_U32(p.cells_x));
  const rm_heightmap_cell c =
      rm_heightmap_column(p, src, rm_hm_voxel_x(p, i), rm_hm_voxel_y(p, j), p.reference_z);
  rm_hm_store(p, src, out, RM_I32(g), c, p.reference_z);
}

/* Flood fill, work-item g of ring k (rm_hm_ring_size(k) items); ring k - 1 must be complete. */
RAYMAP_FN void rm_hm_fill_item(rm_heightmap_params p, rm_hm_sources src, rm_hm_layers out, rm_i32 k,
                               rm_u32 g) {
  if (g >= rm_hm_ring_size(k)) {
    return;
  }
  rm_i32 di = 0;
  rm_i32 dj = 0;
  if (k > 0) {
    rm_hm_ring_cell(k, RM_I32(g), &di, &dj);
  }
  const rm_i32 i = p.seed_i + di;
  const rm_i32 j = p.seed_j + dj;
  if (i < 0 || j < 0 || i >= p.cells_x || j >= p.cells_y) {
    return;
  }
  const float reference =
      k == 0 ? p.reference_z
             : rm_hm_fill_reference(p, out.elevation, out.kind, out.reference, i, j, di, dj, k);
  const rm_heightmap_cell c =
      rm_heightmap_column(p, src, rm_hm_voxel_x(p, i), rm_hm_voxel_y(p, j), reference);
  rm_hm_store(p, src, out, i + j * p.cells_x, c, reference);
}

#endif /* RAYMAP_KERNELS_COMMON_HEIGHTMAP_H */
