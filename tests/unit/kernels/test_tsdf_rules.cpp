// SPDX-License-Identifier: BSD-3-Clause
// The TSDF rules of kernels/common/tsdf.h on their own: the free-space shortcut never takes a voxel
// whose distance is below the truncation, fusion averages and truncates, the drop-off behind the
// surface, an agreeing ray leaves a voxel's distance exactly, and the free-space path of the update
// equals the full rule.
#include <algorithm>
#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "kernels/common/line_walk.h"
#include "kernels/common/tsdf.h"

namespace raymap {
namespace {

constexpr rm_tsdf_params kParams{0.3f, 1.0e4f, 0.1f, 0.1f};  // tau, max weight, eps, resolution

// Random rays in any direction, walked whole, both ways, with several distances at the sample
// end: every voxel rm_tsdf_is_free calls free has a computed distance of at least tau (so the
// shortcut gives exactly the update the full rule would).
TEST(TsdfRules, TheFreeSpaceShortcutOnlyTakesVoxelsAtLeastTauInFront) {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<float> local(0.0f, 1.0f);
  std::uniform_real_distribution<float> extent(-60.0f, 60.0f);
  std::uint64_t free = 0;
  std::uint64_t band = 0;
  for (int i = 0; i < 3000; ++i) {
    const rm_vec3f start = rm_vec3f_make(local(rng), local(rng), local(rng));
    const rm_vec3f end =
        rm_vec3f_make(start.x + extent(rng), start.y + extent(rng), start.z + extent(rng) * 0.2f);
    const rm_vec3i end_voxel =
        rm_vec3i_make(static_cast<int>(std::floor(end.x)), static_cast<int>(std::floor(end.y)),
                      static_cast<int>(std::floor(end.z)));
    const rm_line_walk_ray ray = rm_line_walk_ray_make(start, end, end_voxel);
    const float end_sdf = i % 3 == 0 ? -kParams.truncation : (i % 3 == 1 ? 0.7f : RM_TSDF_FREE);
    for (const int reverse : {0, 1}) {
      const rm_tsdf_ray r = rm_tsdf_ray_make(&ray, reverse, end_sdf);
      const float bound = rm_tsdf_free_bound(&r, kParams);
      rm_line_walk w;
      const rm_vec3i lo = rm_vec3i_make(-1000, -1000, -1000);
      const rm_vec3i hi = rm_vec3i_make(1000, 1000, 1000);
      rm_line_walk_init_span(&w, &ray, 0.0f, 1.0f, lo, hi, 1, 1);
      do {
        const float sdf = rm_tsdf_sdf(&r, rm_vec3i_make(w.x, w.y, w.z), kParams.resolution);
        if (rm_tsdf_is_free(rm_line_walk_t_enter(&w), bound, reverse) != 0) {
          ++free;
          ASSERT_GE(sdf, kParams.truncation) << "ray " << i << (reverse ? " reverse" : "");
        } else {
          ++band;
        }
      } while (rm_line_walk_next(&w) >= 0);
    }
  }
  EXPECT_GT(free, 10 * band);  // and the shortcut does take most voxels
}

TEST(TsdfRules, FusionAveragesTheTruncatedDistanceAndCapsTheWeight) {
  rm_tsdf_voxel v{0.0f, 0.0f};
  rm_tsdf_update(&v, 0.1f, kParams);
  EXPECT_EQ(v.distance, 0.1f);
  EXPECT_EQ(v.weight, 1.0f);
  rm_tsdf_update(&v, 5.0f, kParams);  // truncated to 0.3 before the average
  EXPECT_NEAR(v.distance, 0.2f, 1e-7f);
  EXPECT_EQ(v.weight, 2.0f);
  rm_tsdf_params capped = kParams;
  capped.max_weight = 2.0f;
  rm_tsdf_update(&v, -0.05f, capped);
  EXPECT_NEAR(v.distance, (0.2f * 2.0f - 0.05f) / 3.0f, 1e-7f);
  EXPECT_EQ(v.weight, 2.0f);
}

TEST(TsdfRules, TheWeightDropsOffBehindTheSurfaceAndNothingBeyondTauIsUpdated) {
  EXPECT_EQ(rm_tsdf_weight(0.2f, kParams), 1.0f);
  EXPECT_EQ(rm_tsdf_weight(-0.1f, kParams), 1.0f);
  EXPECT_NEAR(rm_tsdf_weight(-0.2f, kParams), 0.5f, 1e-6f);
  EXPECT_EQ(rm_tsdf_weight(-0.3f, kParams), 0.0f);
  rm_tsdf_params constant = kParams;
  constant.dropoff = 0.0f;
  EXPECT_EQ(rm_tsdf_weight(-0.29f, constant), 1.0f);
  rm_tsdf_voxel v{0.05f, 3.0f};
  rm_tsdf_update(&v, -0.31f, kParams);
  EXPECT_EQ(v.distance, 0.05f);
  EXPECT_EQ(v.weight, 3.0f);
}

TEST(TsdfRules, AnAgreeingRayLeavesTheDistanceExactly) {
  // (0.3 * 7 + 0.3) / 8 in float may round away from 0.3f; the rule keeps 0.3f.
  rm_tsdf_voxel v{0.3f, 7.0f};
  rm_tsdf_update(&v, 4.0f, kParams);
  EXPECT_EQ(v.distance, 0.3f);
  EXPECT_EQ(v.weight, 8.0f);
}

// rm_tsdf_update's free-space path (+tau on a voxel at +tau: the weight alone) gives the pair the
// full rule gives, rm_tsdf_fuse with the ray's weight, for every weight up to and at the cap.
TEST(TsdfRules, TheFreeSpacePathOfTheUpdateEqualsTheFullRule) {
  rm_tsdf_params capped = kParams;
  capped.max_weight = 50.0f;
  std::mt19937_64 rng(9);
  std::uniform_real_distribution<float> weight(0.0f, 60.0f);
  for (int i = 0; i < 100000; ++i) {
    const float w = i % 10 == 0 ? capped.max_weight : std::min(weight(rng), capped.max_weight);
    const rm_tsdf_voxel start{capped.truncation, w};
    rm_tsdf_voxel updated = start;
    rm_tsdf_update(&updated, capped.truncation, capped);
    const rm_tsdf_voxel full =
        rm_tsdf_fuse(start, capped.truncation, rm_tsdf_weight(capped.truncation, capped), capped);
    ASSERT_EQ(updated.distance, full.distance) << "weight " << w;
    ASSERT_EQ(updated.weight, full.weight) << "weight " << w;
  }
}

}  // namespace
}  // namespace raymap
