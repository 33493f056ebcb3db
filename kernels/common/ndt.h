/* SPDX-License-Identifier: BSD-3-Clause */
/* NDT-OM and NDT-TM update rules (normal-distributions-transform occupancy and traversability
 * maps), shared by the CPU reference, OpenCL and CUDA. Sources: Saarinen et al. 2013, "3D normal
 * distributions transform occupancy maps"; Ahtiainen et al. 2017, "Normal distributions transform
 * traversability maps"; OHM's formulation (shared/reference/ohm-notes.md, sections 2.5 and 2.6).
 *
 * Frame and units: everything here is in voxel units in the frame of the voxel being updated, its
 * minimum corner at 0 (the frame of the voxel mean, voxel_mean.h): a sample in the voxel lies in
 * [0,1]^3 and 1 unit is `resolution` metres. Distances in metres are converted once on the host
 * (rm_ndt_params). Covariances are in voxel units squared.
 *
 * The voxel's Gaussian is the mean and the maximum-likelihood (population) covariance of its
 * samples, P = 1/n sum (z - mu)(z - mu)^T. It is kept as a lower-triangular factor S with
 * P = S S^T and updated per sample with the square-root form of the recursive covariance
 *   P' = n/(n+1) P + n/(n+1)^2 d d^T,  d = z - mu,
 * that is S' S'^T = (a S)(a S)^T + (b d)(b d)^T with a = sqrt(n/(n+1)), b = sqrt(n)/(n+1): a
 * rank-one Cholesky update done with Givens rotations, which never divides by a diagonal element,
 * so it is exact for singular factors (one sample, coplanar or collinear samples). The factor keeps
 * the sample covariance itself, not a regularised one, so it can be checked against a batch
 * covariance. Where a rule needs the inverse, it uses P + r^2 I (r = rm_ndt_params.regulariser,
 * 0.1 voxel by default, OHM's seed sigma), refactored with a 3x3 Cholesky: a planar surfel stays a
 * flat but invertible ellipsoid.
 *
 * Semantics of a batch on every backend: the misses of all rays of the batch are applied first,
 * against the Gaussians as they were at the start of the batch, then the hits, voxel by voxel, in
 * ray order. (A device cannot fold a covariance with single-word atomics, so it folds the hits of a
 * voxel in one work-item after the misses; the CPU does the same so that the backends agree.) */
#ifndef RAYMAP_KERNELS_COMMON_NDT_H
#define RAYMAP_KERNELS_COMMON_NDT_H

#include "line_walk.h"
#include "occupancy.h"
#include "portable.h"
#include "ray.h"

#if defined(__OPENCL_C_VERSION__)
#define RM_EXPF(x) exp(x)
#define RM_LOGF(x) log(x)
#else
#define RM_EXPF(x) expf(x)
#define RM_LOGF(x) logf(x)
#endif

/* One voxel of the NDT layer (40 bytes). count == 0: no Gaussian yet (the clear value is all
 * zero). The factor is packed by rows of the lower triangle: s[0] = S00, s[1] = S10, s[2] = S11,
 * s[3] = S20, s[4] = S21, s[5] = S22. */
typedef struct rm_ndt_voxel {
  float mean_x; /* sample mean, voxel units from the voxel's minimum corner */
  float mean_y;
  float mean_z;
  float s[6];   /* square-root covariance factor, voxel units */
  rm_u32 count; /* samples in the Gaussian (since its last reinitialisation); saturates */
} rm_ndt_voxel;

/* NDT-TM: reflections and pass-throughs of a voxel (8 bytes); permeability = miss / (hit + miss).
 */
typedef struct rm_ndt_hit_miss {
  rm_u32 hit;
  rm_u32 miss;
} rm_ndt_hit_miss;

/* NDT-TM: running mean and variance of the return intensity in a voxel (8 bytes), in the sensor's
 * intensity units. */
typedef struct rm_ndt_intensity {
  float mean;
  float variance;
} rm_ndt_intensity;

/* Parameters, converted to voxel units by the host (src/map/map_params.hpp has the defaults in
 * metres and probabilities). */
typedef struct rm_ndt_params {
  float sensor_noise;    /* sigma of a range measurement, voxel units (0.05 m by default) */
  float regulariser;     /* r: sigma added to every axis where the inverse is needed, voxel units */
  float adaptation_rate; /* alpha in [0,1]: how much a ray through the surfel lowers occupancy */
  float reinit_threshold;  /* log-odds: a voxel below it with reinit_count samples starts afresh */
  rm_u32 reinit_count;     /* samples a Gaussian needs before it can be reinitialised */
  rm_u32 sample_threshold; /* samples before the Gaussian shapes misses (fewer: a plain miss) */
  float initial_intensity_variance; /* intensity variance after the first sample */
  rm_u32 traversability;            /* 1: NDT-TM (hit/miss counts and intensity), 0: NDT-OM */
} rm_ndt_params;

/* ---- the square-root covariance ---- */

/* S <- factor of (a S)(a S)^T + x x^T: Givens rotations of each column of S against x. Exact
 * arithmetic aside, S stays lower-triangular with a non-negative diagonal. */
RAYMAP_FN void rm_ndt_rank_one_update(float* s, float a, rm_vec3f x_in) {
  float x[3];
  int k;
  x[0] = x_in.x;
  x[1] = x_in.y;
  x[2] = x_in.z;
  for (k = 0; k < 6; ++k) {
    s[k] *= a;
  }
  for (k = 0; k < 3; ++k) {
    /* s index of (row i, column k): i * (i + 1) / 2 + k */
    int diag = k * (k + 1) / 2 + k;
    float lkk = s[diag];
    float r = RM_SQRTF(lkk * lkk + x[k] * x[k]);
    float c;
    float sn;
    int i;
    if (r == 0.0f) {
      continue; /* column and x both zero here: nothing to rotate */
    }
    c = lkk / r;
    sn = x[k] / r;
    s[diag] = r;
    for (i = k + 1; i < 3; ++i) {
      int e = i * (i + 1) / 2 + k;
      float t = s[e];
      s[e] = c * t + sn * x[i];
      x[i] = c * x[i] - sn * t;
    }
  }
}

/* P = S S^T as 6 packed entries (same packing as S). */
RAYMAP_FN void rm_ndt_covariance(const float* s, float* p) {
  p[0] = s[0] * s[0];
  p[1] = s[1] * s[0];
  p[2] = s[1] * s[1] + s[2] * s[2];
  p[3] = s[3] * s[0];
  p[4] = s[3] * s[1] + s[4] * s[2];
  p[5] = s[3] * s[3] + s[4] * s[4] + s[5] * s[5];
}

/* Cholesky factor L of S S^T + r^2 I (positive definite for r > 0). */
RAYMAP_FN void rm_ndt_regularised_factor(const float* s, float r, float* l) {
  float p[6];
  float r2 = r * r;
  rm_ndt_covariance(s, p);
  p[0] += r2;
  p[2] += r2;
  p[5] += r2;
  l[0] = RM_SQRTF(p[0]);
  l[1] = p[1] / l[0];
  l[2] = RM_SQRTF(RM_FMAXF(p[2] - l[1] * l[1], r2 * 1e-6f));
  l[3] = p[3] / l[0];
  l[4] = (p[4] - l[3] * l[1]) / l[2];
  l[5] = RM_SQRTF(RM_FMAXF(p[5] - l[3] * l[3] - l[4] * l[4], r2 * 1e-6f));
}

/* y = L^-1 v (forward substitution). */
RAYMAP_FN rm_vec3f rm_ndt_solve(const float* l, rm_vec3f v) {
  rm_vec3f y;
  y.x = v.x / l[0];
  y.y = (v.y - l[1] * y.x) / l[2];
  y.z = (v.z - l[3] * y.x - l[4] * y.y) / l[5];
  return y;
}

RAYMAP_FN float rm_ndt_dot(rm_vec3f a, rm_vec3f b) { return a.x * b.x + a.y * b.y + a.z * b.z; }

RAYMAP_FN rm_vec3f rm_ndt_sub(rm_vec3f a, rm_vec3f b) {
  return rm_vec3f_make(a.x - b.x, a.y - b.y, a.z - b.z);
}

RAYMAP_FN rm_vec3f rm_ndt_mean(const rm_ndt_voxel* v) {
  return rm_vec3f_make(v->mean_x, v->mean_y, v->mean_z);
}

/* Folds one sample (voxel frame) into the Gaussian. */
RAYMAP_FN void rm_ndt_fold_sample(rm_ndt_voxel* v, rm_vec3f z) {
  float n = RM_F32(v->count);
  float inv = 1.0f / (n + 1.0f);
  float root_n = RM_SQRTF(n);
  rm_vec3f d = rm_ndt_sub(z, rm_ndt_mean(v));
  rm_vec3f bd = rm_vec3f_make(d.x * root_n * inv, d.y * root_n * inv, d.z * root_n * inv);
  /* a = sqrt(n) / sqrt(n + 1), not sqrt(n / (n + 1)): the quotient lies just below 1, where
   * consecutive n round to the same few floats with errors of one sign, and the factor scales
   * everything folded before; over 10^4 samples that bias reached 1e-4 of the covariance, the
   * two square roots round independently and keep it near 5e-6 (tests/unit/kernels). */
  rm_ndt_rank_one_update(v->s, root_n / RM_SQRTF(n + 1.0f), bd);
  v->mean_x += d.x * inv;
  v->mean_y += d.y * inv;
  v->mean_z += d.z * inv;
  v->count = v->count == 0xFFFFFFFFu ? v->count : v->count + 1u;
}

/* Starts the Gaussian afresh at one sample. */
RAYMAP_FN void rm_ndt_reset(rm_ndt_voxel* v, rm_vec3f z) {
  int k;
  v->mean_x = z.x;
  v->mean_y = z.y;
  v->mean_z = z.z;
  for (k = 0; k < 6; ++k) {
    v->s[k] = 0.0f;
  }
  v->count = 1u;
}

/* ---- how a ray meets a voxel's Gaussian ---- */

/* The point of the ray segment from `origin` to `sample` (voxel frame) that is most likely under
 * the voxel's (regularised) Gaussian, and the two likelihoods the rules use. Unlike OHM, the point
 * is kept on the segment: a ray gives no evidence beyond its sample. */
typedef struct rm_ndt_ray_fit {
  float p_gaussian; /* exp(-1/2 Mahalanobis^2) of the point under the voxel's Gaussian */
  float p_sample;   /* exp(-1/2 |point - sample|^2 / sensor_noise^2): the point is the return */
} rm_ndt_ray_fit;

RAYMAP_FN rm_ndt_ray_fit rm_ndt_fit_ray(const rm_ndt_voxel* v, rm_vec3f origin, rm_vec3f sample,
                                        rm_ndt_params p) {
  rm_ndt_ray_fit fit;
  float l[6];
  rm_vec3f dir = rm_ndt_sub(sample, origin);
  float length = RM_SQRTF(rm_ndt_dot(dir, dir));
  rm_vec3f a;
  rm_vec3f b;
  float aa;
  float t = 0.0f;
  rm_vec3f m;
  rm_vec3f point;
  rm_vec3f to_sample;
  float noise2 = p.sensor_noise * p.sensor_noise;
  rm_ndt_regularised_factor(v->s, p.regulariser, l);
  if (length > 0.0f) {
    dir = rm_vec3f_make(dir.x / length, dir.y / length, dir.z / length);
  }
  /* Mahalanobis distance of origin + t dir: |b + t a|^2 with a = L^-1 dir, b = L^-1 (origin - mu);
   * minimal at t = -(a.b)/(a.a). */
  a = rm_ndt_solve(l, dir);
  b = rm_ndt_solve(l, rm_ndt_sub(origin, rm_ndt_mean(v)));
  aa = rm_ndt_dot(a, a);
  if (aa > 0.0f) {
    t = RM_FMINF(RM_FMAXF(-rm_ndt_dot(a, b) / aa, 0.0f), length);
  }
  m = rm_vec3f_make(b.x + t * a.x, b.y + t * a.y, b.z + t * a.z);
  point = rm_vec3f_make(origin.x + t * dir.x, origin.y + t * dir.y, origin.z + t * dir.z);
  to_sample = rm_ndt_sub(point, sample);
  fit.p_gaussian = RM_EXPF(-0.5f * rm_ndt_dot(m, m));
  fit.p_sample = RM_EXPF(-0.5f * rm_ndt_dot(to_sample, to_sample) / noise2);
  return fit;
}

/* ---- where a ray is, in a voxel's frame ---- */

/* Origin and sample of a walked ray in the frame of the voxel `voxel` (relative to the walk's start
 * voxel, as rm_line_walk's x, y, z): the walk starts at the origin, or at the sample when
 * sample_is_start (reverse walk). */
RAYMAP_FN void rm_ndt_ray_in_voxel(const rm_line_walk_ray* ray, int sample_is_start, rm_vec3i voxel,
                                   rm_vec3f* origin, rm_vec3f* sample) {
  rm_vec3f q = rm_vec3f_make(RM_F32(voxel.x), RM_F32(voxel.y), RM_F32(voxel.z));
  rm_vec3f start = rm_ndt_sub(ray->start, q);
  rm_vec3f end =
      rm_vec3f_make(start.x + ray->extent.x, start.y + ray->extent.y, start.z + ray->extent.z);
  *origin = sample_is_start ? end : start;
  *sample = sample_is_start ? start : end;
}

/* A prepared ray's origin in the frame of its sample voxel. */
RAYMAP_FN rm_vec3f rm_ndt_origin_at_sample(rm_prepared_ray ray) {
  return rm_vec3f_make(ray.origin_local.x + RM_F32(ray.origin_voxel.x - ray.sample_voxel.x),
                       ray.origin_local.y + RM_F32(ray.origin_voxel.y - ray.sample_voxel.y),
                       ray.origin_local.z + RM_F32(ray.origin_voxel.z - ray.sample_voxel.z));
}

/* ---- the update rules ---- */

/* Whether the Gaussian shapes the misses of a voxel holding `count` samples. */
RAYMAP_FN int rm_ndt_shapes_misses(rm_u32 count, rm_ndt_params p) {
  return count >= p.sample_threshold && count > 0u;
}

/* True when no NDT miss can change a voxel whose occupancy is `value`: NDT-OM at the lower clamp
 * (NDT-TM still counts the pass there, so it is never true for NDT-TM). */
RAYMAP_FN int rm_ndt_miss_is_noop(float value, rm_occupancy_params occ, rm_ndt_params p) {
  return p.traversability == 0u && value <= occ.clamp_min;
}

/* NDT miss: a ray from `origin` to `sample` (voxel frame) passes through a voxel whose occupancy
 * is `value`; has_sample is 0 when the ray's end is not a return (RM_RAY_END_HIT unset). Returns
 * the new occupancy. Unobserved voxels and voxels with fewer than sample_threshold samples take a
 * plain miss; otherwise p_update = 1/2 - alpha/2 p_gaussian (1 - p_sample),  value +=
 * logit(p_update), so a ray beside the surfel (p_gaussian ~ 0) or ending on it (p_sample ~ 1)
 * changes nothing and a ray straight through it lowers the log-odds by up to logit(1/2 - alpha/2).
 * *is_miss (NDT-TM) says whether the pass counts as a miss of the voxel: it does unless the ray
 * crossed the surfel (p_gaussian (1 - p_sample) >= alpha/2). */
RAYMAP_FN float rm_ndt_miss(float value, const rm_ndt_voxel* v, rm_vec3f origin, rm_vec3f sample,
                            int has_sample, rm_occupancy_params occ, rm_ndt_params p,
                            int* is_miss) {
  rm_ndt_ray_fit fit;
  float product;
  float p_update;
  if (!rm_occupancy_observed(value) || rm_ndt_miss_is_noop(value, occ, p)) {
    /* Unobserved: a plain miss. At the lower clamp no miss can change the value, so NDT-OM does
     * not read the Gaussian (most voxels a ray crosses are free space at the clamp, and the
     * 40-byte Gaussian costs a cache line per voxel); NDT-TM still needs it to count the pass. */
    *is_miss = 1;
    return rm_occupancy_miss(value, occ);
  }
  if (!rm_ndt_shapes_misses(v->count, p)) {
    *is_miss = 1;
    return rm_occupancy_miss(value, occ);
  }
  fit = rm_ndt_fit_ray(v, origin, sample, p);
  if (!has_sample) {
    fit.p_sample = 0.0f; /* the ray ends without a return there (clipped, or an inner segment) */
  }
  product = fit.p_gaussian * (1.0f - fit.p_sample);
  *is_miss = product < 0.5f * p.adaptation_rate;
  p_update = 0.5f - 0.5f * p.adaptation_rate * product;
  return RM_FMAXF(value + RM_LOGF(p_update / (1.0f - p_update)), occ.clamp_min);
}

/* Whether a hit reinitialises the Gaussian: there is none yet, or the voxel has become likely
 * free (value below reinit_threshold) although its Gaussian holds reinit_count samples: the
 * surface it described has gone (a transient object). `value` is the occupancy before the hit. */
RAYMAP_FN int rm_ndt_reinitialises(float value, const rm_ndt_voxel* v, rm_ndt_params p) {
  return v->count == 0u ||
         (rm_occupancy_observed(value) && value < p.reinit_threshold && v->count >= p.reinit_count);
}

/* NDT hit of one sample `sample` (voxel frame) of a ray from `origin`, with return intensity
 * `intensity`, on a voxel whose occupancy is *value. Updates the occupancy (a plain hit), the
 * Gaussian (reinitialised when rm_ndt_reinitialises) and, for NDT-TM (hit_miss and intensity not
 * null), the hit/miss counts and the intensity statistics:
 *  - counts restart with the Gaussian; the hit counts as a hit when the Gaussian is new, too young
 *    to judge (< sample_threshold samples) or the ray ends on its surfel (p_gaussian p_sample >=
 *    alpha/2), and as a miss when the ray crossed the surfel and ended elsewhere (p_gaussian >=
 *    alpha/2 and p_gaussian (1 - p_sample) < alpha/2: OHM's rule);
 *  - intensity: the running mean and population variance, the variance starting at
 *    initial_intensity_variance (a prior worth one sample). */
RAYMAP_FN void rm_ndt_hit(float* value, rm_ndt_voxel* v, rm_ndt_hit_miss* hit_miss,
                          rm_ndt_intensity* intensity, rm_vec3f origin, rm_vec3f sample,
                          float sample_intensity, rm_occupancy_params occ, rm_ndt_params p) {
  int reset = rm_ndt_reinitialises(*value, v, p);
  if (hit_miss != 0 && intensity != 0) {
    if (reset) {
      hit_miss->hit = 1u;
      hit_miss->miss = 0u;
      intensity->mean = sample_intensity;
      intensity->variance = p.initial_intensity_variance;
    } else {
      float n = RM_F32(v->count);
      float delta = sample_intensity - intensity->mean;
      int young = !rm_ndt_shapes_misses(v->count, p);
      rm_ndt_ray_fit fit;
      fit.p_gaussian = 0.0f;
      fit.p_sample = 0.0f;
      if (!young) {
        fit = rm_ndt_fit_ray(v, origin, sample, p);
      }
      if (young || fit.p_gaussian * fit.p_sample >= 0.5f * p.adaptation_rate) {
        hit_miss->hit += hit_miss->hit == 0xFFFFFFFFu ? 0u : 1u;
      } else if (fit.p_gaussian >= 0.5f * p.adaptation_rate &&
                 fit.p_gaussian * (1.0f - fit.p_sample) < 0.5f * p.adaptation_rate) {
        hit_miss->miss += hit_miss->miss == 0xFFFFFFFFu ? 0u : 1u;
      }
      intensity->mean += delta / (n + 1.0f);
      intensity->variance = (n * intensity->variance + n * delta * delta / (n + 1.0f)) / (n + 1.0f);
    }
  }
  if (reset) {
    rm_ndt_reset(v, sample);
  } else {
    rm_ndt_fold_sample(v, sample);
  }
  *value = rm_occupancy_hit(*value, occ);
}

/* NDT-TM: counts a pass-through reported by rm_ndt_miss. Callers count the passes of voxels that
 * hold a sample (count > 0) only: the first hit restarts the counts (rm_ndt_hit), so passes before
 * it would be dropped anyway, and free space is spared a write per voxel crossed. */
RAYMAP_FN void rm_ndt_count_miss(rm_ndt_hit_miss* hit_miss, int is_miss) {
  if (is_miss && hit_miss->miss != 0xFFFFFFFFu) {
    hit_miss->miss += 1u;
  }
}

#endif /* RAYMAP_KERNELS_COMMON_NDT_H */
