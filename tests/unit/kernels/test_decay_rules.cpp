// SPDX-License-Identifier: BSD-3-Clause
// The decay-rate rules of kernels/common/decay.h: the metres of a voxel added after the walk has
// stepped past it (rm_decay_stepped_voxel_metres, the loop of the CPU and device traversal) are
// the same float as those computed before the step (rm_decay_voxel_metres), on random, axis-
// aligned and grid-aligned rays, whole and cut into spans.
#include <cmath>
#include <cstdint>
#include <random>
#include <utility>

#include <gtest/gtest.h>

#include "kernels/common/decay.h"
#include "kernels/common/line_walk.h"

namespace raymap {
namespace {

/// Walks `w` to its end and checks every voxel but the last both ways; returns the voxels.
int checkWalk(rm_line_walk w, float ray_metres) {
  int voxels = 1;
  while (w.steps_left > 0) {
    const float before = rm_decay_voxel_metres(&w, ray_metres);
    const float t_left_enter = rm_line_walk_t_enter(&w);
    rm_line_walk_step(&w);
    const float after = rm_decay_stepped_voxel_metres(t_left_enter, &w, ray_metres);
    EXPECT_EQ(before, after) << "voxel " << voxels << " of the walk";
    if (before != after) {
      return voxels;
    }
    ++voxels;
  }
  return voxels;
}

rm_vec3i floorOf(rm_vec3f p) {
  return rm_vec3i_make(static_cast<rm_i32>(std::floor(p.x)), static_cast<rm_i32>(std::floor(p.y)),
                       static_cast<rm_i32>(std::floor(p.z)));
}

TEST(DecayRules, MetresAfterTheStepEqualMetresBeforeItOnEveryVoxel) {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<float> inside(0.0f, 1.0f);
  std::uniform_real_distribution<float> extent(-40.0f, 40.0f);
  std::uniform_int_distribution<int> whole(-12, 12);
  std::uniform_int_distribution<int> kind(0, 3);
  long long voxels = 0;
  for (int i = 0; i < 20000; ++i) {
    rm_vec3f start = rm_vec3f_make(inside(rng), inside(rng), inside(rng));
    rm_vec3f end =
        rm_vec3f_make(start.x + extent(rng), start.y + extent(rng), start.z + extent(rng));
    switch (kind(rng)) {
      case 1:  // along one axis
        end.y = start.y;
        end.z = start.z;
        break;
      case 2:  // from and to voxel corners: crossings tie on several axes
        start = rm_vec3f_make(0.0f, 0.0f, 0.0f);
        end = rm_vec3f_make(static_cast<float>(whole(rng)), static_cast<float>(whole(rng)),
                            static_cast<float>(whole(rng)));
        break;
      case 3:  // short rays
        end = rm_vec3f_make(start.x + 0.01f * extent(rng), start.y + 0.01f * extent(rng),
                            start.z + 0.01f * extent(rng));
        break;
      default:
        break;
    }
    const rm_line_walk_ray ray = rm_line_walk_ray_make(start, end, floorOf(end));
    const float ray_metres =
        0.1f * std::sqrt(ray.extent.x * ray.extent.x + ray.extent.y * ray.extent.y +
                         ray.extent.z * ray.extent.z);
    rm_line_walk whole_walk;
    rm_line_walk_init(&whole_walk, start, end, floorOf(end));
    voxels += checkWalk(whole_walk, ray_metres);
    // A span inside the ray, its ends the voxels holding its end points (as a region piece).
    float t0 = inside(rng);
    float t1 = inside(rng);
    if (t0 > t1) {
      std::swap(t0, t1);
    }
    const rm_vec3i far_lo = rm_vec3i_make(-1000, -1000, -1000);
    const rm_vec3i far_hi = rm_vec3i_make(1000, 1000, 1000);
    rm_line_walk span;
    rm_line_walk_init_span(&span, &ray, t0, t1, far_lo, far_hi, 0, 0);
    voxels += checkWalk(span, ray_metres);
    if (HasFailure()) {
      FAIL() << "ray " << i;
    }
  }
  EXPECT_GT(voxels, 500000);
}

}  // namespace
}  // namespace raymap
