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
 *  - a *surface* candidate is an occupied voxel; its height is the voxel mean's z when the mean
 *    layer is present and has samples, else the voxel centre;
 *  - a *virtual surface* candidate (only with RM_HM_FLAG_VIRTUAL) is the lowest observed free voxel
 *    of a run of non-occupied voxels whose voxel below is unobserved: free space seen over space
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
 * the same result. */
#ifndef RAYMAP_KERNELS_COMMON_HEIGHTMAP_H
#define RAYMAP_KERNELS_COMMON_HEIGHTMAP_H

#include "key_math.h"
#include "occupancy.h"
#include "portable.h"
#include "voxel_mean.h"

/* Cell kinds (the `kind` layer). Stable values: they are published and written to files. */
#define RM_HM_UNKNOWN 0u
#define RM_HM_SURFACE 1u
#define RM_HM_VIRTUAL 2u
#define RM_HM_VACANT 3u

/* Parameter flags. */
#define RM_HM_FLAG_VIRTUAL 1 /* look for virtual surfaces */
#define RM_HM_FLAG_MEAN 2    /* the mean layer is present: use it for surface heights */
#define RM_HM_FLAG_FILL 4    /* flood-fill mode (else planar) */

/* Region table entry of a region the map does not hold (all its voxels are unobserved). */
#define RM_HM_NO_REGION 0xFFFFFFFFu

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
  rm_i32 flags;             /* RM_HM_FLAG_* */
  float resolution;         /* voxel edge, metres */
  float reference_z;        /* planar reference / fill seed reference, metres */
  float floor_depth;        /* metres searched below the reference */
  float ceiling_height;     /* metres searched above the reference */
  float min_clearance;      /* metres */
  float occupied_threshold; /* log-odds: occupied when value >= threshold */
} rm_heightmap_params;

/* The result of one column search. */
typedef struct rm_heightmap_cell {
  float elevation; /* metres, world z; NaN unless surface or virtual */
  float clearance; /* metres; +inf when open above; NaN unless surface or virtual */
  rm_u32 kind;     /* RM_HM_* */
  rm_u32 samples;  /* samples in the surface voxel (voxel mean count); 0 otherwise */
} rm_heightmap_cell;

/* Voxel states as the search sees them. */
#define RM_HM_STATE_UNOBSERVED 0
#define RM_HM_STATE_FREE 1
#define RM_HM_STATE_OCCUPIED 2

RAYMAP_FN rm_i32 rm_hm_state(float value, float threshold) {
  if (!rm_occupancy_observed(value)) {
    return RM_HM_STATE_UNOBSERVED;
  }
  return value >= threshold ? RM_HM_STATE_OCCUPIED : RM_HM_STATE_FREE;
}

/* Region-table entry (pool slot) of the region holding voxel z of a column, or RM_HM_NO_REGION. */
RAYMAP_FN rm_u32 rm_hm_region_slot(RAYMAP_GLOBAL const rm_u32* table, rm_heightmap_params p,
                                   rm_i32 rx, rm_i32 ry, rm_i32 rz) {
  rm_i32 tx = rx - p.region_x0;
  rm_i32 ty = ry - p.region_y0;
  rm_i32 tz = rz - p.region_z0;
  if (tx < 0 || ty < 0 || tz < 0 || tx >= p.regions_x || ty >= p.regions_y || tz >= p.regions_z) {
    return RM_HM_NO_REGION;
  }
  return table[tx + p.regions_x * (ty + p.regions_y * tz)];
}

/* A candidate waiting for the next occupied voxel above it, which fixes its clearance. */
typedef struct rm_hm_candidate {
  float height;
  rm_u32 kind; /* RM_HM_SURFACE, RM_HM_VIRTUAL, or RM_HM_UNKNOWN for none */
  rm_u32 samples;
} rm_hm_candidate;

RAYMAP_FN rm_hm_candidate rm_hm_no_candidate(void) {
  rm_hm_candidate c;
  c.height = 0.0f;
  c.kind = RM_HM_UNKNOWN;
  c.samples = 0u;
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
  }
}

/* Searches the column of global voxel (vx, vy) around `reference` (metres). `occupancy` and `mean`
 * are whole layers indexed by slot * voxels-per-region + local index; `mean` is only read with
 * RM_HM_FLAG_MEAN. */
RAYMAP_FN rm_heightmap_cell rm_heightmap_column(rm_heightmap_params p,
                                                RAYMAP_GLOBAL const rm_u32* table,
                                                RAYMAP_GLOBAL const float* occupancy,
                                                RAYMAP_GLOBAL const rm_voxel_mean* mean, rm_i32 vx,
                                                rm_i32 vy, float reference) {
  rm_heightmap_cell best;
  best.elevation = RM_F32(NAN);
  best.clearance = RM_F32(NAN);
  best.kind = RM_HM_UNKNOWN;
  best.samples = 0u;
  float best_distance = RM_INF;

  const float res = p.resolution;
  const rm_i32 n = p.region_voxels;
  const rm_u32 voxels_per_region = RM_U32(n * n * n);
  const rm_u32 plane = RM_U32(n * n);
  /* Voxels whose centre lies in [reference - floor, reference + ceiling]. */
  rm_i32 z_lo = rm_floor_i32((reference - p.floor_depth) / res + 0.5f);
  rm_i32 z_hi = rm_floor_i32((reference + p.ceiling_height) / res - 0.5f);
  z_lo = z_lo < p.box_z_min ? p.box_z_min : z_lo;
  z_hi = z_hi > p.box_z_max ? p.box_z_max : z_hi;
  if (z_lo > z_hi) {
    return best;
  }
  const rm_i32 rx = rm_floor_div(vx, n);
  const rm_i32 ry = rm_floor_div(vy, n);
  const rm_u32 column = RM_U32((vx - rx * n) + n * (vy - ry * n));
  const int virtual_on = (p.flags & RM_HM_FLAG_VIRTUAL) != 0;
  const int mean_on = (p.flags & RM_HM_FLAG_MEAN) != 0;
  const float virtual_limit = reference + res;

  rm_hm_candidate real = rm_hm_no_candidate();   /* occupied voxel at the bottom of this gap */
  rm_hm_candidate hidden = rm_hm_no_candidate(); /* virtual candidate in this gap */
  rm_i32 previous = RM_HM_STATE_UNOBSERVED;      /* the voxel below z_lo is read first */
  rm_i32 lowest_state = RM_HM_STATE_UNOBSERVED;
  rm_i32 gap_has_virtual = 0;

  /* Walk region by region from the voxel below z_lo up to the top of the box (clearances look
   * above the search range); stop early once a resolved candidate at or above the reference is
   * held, because every later candidate is higher and so farther away. */
  rm_i32 z = z_lo - 1;
  while (z <= p.box_z_max) {
    const rm_i32 rz = rm_floor_div(z, n);
    const rm_i32 region_top = rz * n + n - 1;
    const rm_i32 z_end = region_top < p.box_z_max ? region_top : p.box_z_max;
    const rm_u32 slot = rm_hm_region_slot(table, p, rx, ry, rz);
    int done = 0;
    for (; z <= z_end; ++z) {
      rm_i32 state = RM_HM_STATE_UNOBSERVED;
      rm_u32 index = 0u;
      if (slot != RM_HM_NO_REGION) {
        index = slot * voxels_per_region + column + RM_U32(z - rz * n) * plane;
        state = rm_hm_state(occupancy[index], p.occupied_threshold);
      }
      if (z == z_lo) {
        lowest_state = state;
      }
      if (state == RM_HM_STATE_OCCUPIED) {
        /* The gap below ends here: resolve its candidates. */
        const float ceiling_face = RM_F32(z) * res;
        rm_hm_offer(&best, &best_distance, real, ceiling_face - real.height, reference,
                    p.min_clearance);
        rm_hm_offer(&best, &best_distance, hidden, ceiling_face - hidden.height, reference,
                    p.min_clearance);
        if (best.kind != RM_HM_UNKNOWN && best.elevation >= reference) {
          done = 1;
          break;
        }
        real = rm_hm_no_candidate();
        hidden = rm_hm_no_candidate();
        gap_has_virtual = 0;
        if (z >= z_lo && z <= z_hi) {
          real.kind = RM_HM_SURFACE;
          real.height = (RM_F32(z) + 0.5f) * res;
          if (mean_on) {
            const rm_voxel_mean m = mean[index];
            if (m.count > 0u) {
              real.height = (RM_F32(z) + rm_mean_decode(m.packed, m.count).z) * res;
            }
            real.samples = m.count;
          }
        } else if (z > z_hi) {
          /* Nothing above the search range can become a candidate. */
          done = 1;
          break;
        }
      } else if (state == RM_HM_STATE_FREE && previous == RM_HM_STATE_UNOBSERVED && virtual_on &&
                 !gap_has_virtual && z >= z_lo && z <= z_hi) {
        const float height = RM_F32(z) * res;
        if (height <= virtual_limit) {
          hidden.kind = RM_HM_VIRTUAL;
          hidden.height = height;
          hidden.samples = 0u;
        }
        gap_has_virtual = 1;
      }
      previous = state;
    }
    if (done) {
      break;
    }
  }
  if (z > p.box_z_max) {
    /* Open above: nothing occupied up to the top of the box. */
    rm_hm_offer(&best, &best_distance, real, RM_INF, reference, p.min_clearance);
    rm_hm_offer(&best, &best_distance, hidden, RM_INF, reference, p.min_clearance);
  }
  if (best.kind == RM_HM_UNKNOWN && lowest_state == RM_HM_STATE_FREE) {
    best.kind = RM_HM_VACANT;
  }
  return best;
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
 * the reference each cell was searched around (flood fill reads its parents' values). */
typedef struct rm_hm_layers {
  RAYMAP_GLOBAL float* elevation;
  RAYMAP_GLOBAL float* clearance;
  RAYMAP_GLOBAL rm_u32* kind;
  RAYMAP_GLOBAL rm_u32* samples;
  RAYMAP_GLOBAL float* reference;
} rm_hm_layers;

RAYMAP_FN void rm_hm_store(rm_hm_layers out, rm_i32 index, rm_heightmap_cell c, float reference) {
  out.elevation[index] = c.elevation;
  out.clearance[index] = c.clearance;
  out.kind[index] = c.kind;
  out.samples[index] = c.samples;
  out.reference[index] = reference;
}

/* Planar mode, work-item g of cells_x * cells_y (x fastest, so neighbouring items read
 * neighbouring voxels). */
RAYMAP_FN void rm_hm_planar_item(rm_heightmap_params p, RAYMAP_GLOBAL const rm_u32* table,
                                 RAYMAP_GLOBAL const float* occupancy,
                                 RAYMAP_GLOBAL const rm_voxel_mean* mean, rm_hm_layers out,
                                 rm_u32 g) {
  if (g >= RM_U32(p.cells_x * p.cells_y)) {
    return;
  }
  const rm_i32 i = RM_I32(g % RM_U32(p.cells_x));
  const rm_i32 j = RM_I32(g / RM_U32(p.cells_x));
  const rm_heightmap_cell c = rm_heightmap_column(p, table, occupancy, mean, rm_hm_voxel_x(p, i),
                                                  rm_hm_voxel_y(p, j), p.reference_z);
  rm_hm_store(out, RM_I32(g), c, p.reference_z);
}

/* Flood fill, work-item g of ring k (rm_hm_ring_size(k) items); ring k - 1 must be complete. */
RAYMAP_FN void rm_hm_fill_item(rm_heightmap_params p, RAYMAP_GLOBAL const rm_u32* table,
                               RAYMAP_GLOBAL const float* occupancy,
                               RAYMAP_GLOBAL const rm_voxel_mean* mean, rm_hm_layers out, rm_i32 k,
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
  const rm_heightmap_cell c = rm_heightmap_column(p, table, occupancy, mean, rm_hm_voxel_x(p, i),
                                                  rm_hm_voxel_y(p, j), reference);
  rm_hm_store(out, i + j * p.cells_x, c, reference);
}

#endif /* RAYMAP_KERNELS_COMMON_HEIGHTMAP_H */
