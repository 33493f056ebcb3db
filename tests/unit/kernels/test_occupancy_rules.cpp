// SPDX-License-Identifier: BSD-3-Clause
// Occupancy log-odds arithmetic, voxel mean packing and per-scan marks (kernels/common).
#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "kernels/common/occupancy.h"
#include "kernels/common/scan_mark.h"
#include "kernels/common/voxel_mean.h"
#include "src/map/map_params.hpp"

namespace raymap {
namespace {

TEST(Occupancy, DefaultsMatchTheSpecification) {
  const OccupancyParams p;
  EXPECT_NEAR(p.hit, 2.1972246f, 1e-6f);    // logit(0.9)
  EXPECT_NEAR(p.miss, -0.2006707f, 1e-6f);  // logit(0.45)
  EXPECT_FLOAT_EQ(p.clamp_min, -2.0f);
  EXPECT_FLOAT_EQ(p.clamp_max, 3.511f);
  EXPECT_FLOAT_EQ(p.threshold, 0.0f);
  const OccupancyParams o = OccupancyParams::octomap();
  EXPECT_NEAR(o.hit, 0.8472979f, 1e-6f);    // logit(0.7)
  EXPECT_NEAR(o.miss, -0.4054651f, 1e-6f);  // logit(0.4)
  EXPECT_TRUE(p.validate().has_value());
}

TEST(Occupancy, FirstUpdateStartsFromEvenOdds) {
  const rm_occupancy_params p = OccupancyParams().toKernel();
  EXPECT_FALSE(rm_occupancy_observed(RM_OCC_UNOBSERVED));
  EXPECT_FLOAT_EQ(rm_occupancy_hit(RM_OCC_UNOBSERVED, p), p.hit);
  EXPECT_FLOAT_EQ(rm_occupancy_miss(RM_OCC_UNOBSERVED, p), p.miss);
}

TEST(Occupancy, HitsAndMissesAddAndClamp) {
  const rm_occupancy_params p = OccupancyParams().toKernel();
  float v = RM_OCC_UNOBSERVED;
  v = rm_occupancy_hit(v, p);
  v = rm_occupancy_hit(v, p);
  EXPECT_FLOAT_EQ(v, p.clamp_max);  // 2 * 2.197 > 3.511
  for (int i = 0; i < 100; ++i) {
    v = rm_occupancy_miss(v, p);
  }
  EXPECT_FLOAT_EQ(v, p.clamp_min);
  // From the lower clamp, a hit climbs back by exactly `hit`.
  EXPECT_FLOAT_EQ(rm_occupancy_hit(v, p), p.clamp_min + p.hit);
}

TEST(Occupancy, ThresholdDecidesTheState) {
  const rm_occupancy_params p = OccupancyParams().toKernel();
  EXPECT_TRUE(rm_occupancy_occupied(0.0f, p.threshold));  // at threshold: occupied (>=)
  EXPECT_FALSE(rm_occupancy_occupied(-1e-6f, p.threshold));
  EXPECT_TRUE(rm_occupancy_free(-1e-6f, p.threshold));
  EXPECT_FALSE(rm_occupancy_occupied(RM_OCC_UNOBSERVED, p.threshold));
  EXPECT_FALSE(rm_occupancy_free(RM_OCC_UNOBSERVED, p.threshold));
}

TEST(Occupancy, SequenceMatchesOctoMapArithmetic) {
  // OctoMap: l += update, then clamp; one hit after three misses at 0.7/0.4.
  const rm_occupancy_params p = OccupancyParams::octomap().toKernel();
  float v = RM_OCC_UNOBSERVED;
  for (int i = 0; i < 3; ++i) {
    v = rm_occupancy_miss(v, p);
  }
  v = rm_occupancy_hit(v, p);
  EXPECT_NEAR(v, 3.0 * std::log(0.4 / 0.6) + std::log(0.7 / 0.3), 1e-5);
  EXPECT_TRUE(rm_occupancy_free(v, p.threshold));
}

TEST(Occupancy, ValidationNamesTheProblem) {
  OccupancyParams p;
  p.hit = logOdds(0.4);
  auto bad = p.validate();
  ASSERT_FALSE(bad);
  EXPECT_NE(bad.error().message.find("map.hit_probability"), std::string::npos);
  p = OccupancyParams();
  p.threshold = p.clamp_max + 1.0f;
  ASSERT_FALSE(p.validate());
}

TEST(VoxelMean, EmptyVoxelDecodesToItsCentre) {
  // OHM decodes an unset mean to the voxel corner; ours has no samples -> the centre.
  const rm_vec3f c = rm_mean_decode(0u, 0u);
  EXPECT_FLOAT_EQ(c.x, 0.5f);
  EXPECT_FLOAT_EQ(c.y, 0.5f);
  EXPECT_FLOAT_EQ(c.z, 0.5f);
}

TEST(VoxelMean, EncodeDecodeWithinOneQuantum) {
  std::mt19937 rng(5489);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  for (int i = 0; i < 100000; ++i) {
    const rm_vec3f p{u(rng), u(rng), u(rng)};
    const rm_vec3f d = rm_mean_decode(rm_mean_encode(p), 1u);
    EXPECT_NEAR(d.x, p.x, 0.5f / 1023.0f + 1e-6f);
    EXPECT_NEAR(d.y, p.y, 0.5f / 1023.0f + 1e-6f);
    EXPECT_NEAR(d.z, p.z, 0.5f / 1023.0f + 1e-6f);
  }
  // Out-of-range inputs clamp to the voxel.
  const rm_vec3f d = rm_mean_decode(rm_mean_encode(rm_vec3f{-0.2f, 1.5f, 1.0f}), 1u);
  EXPECT_FLOAT_EQ(d.x, 0.0f);
  EXPECT_FLOAT_EQ(d.y, 1.0f);
  EXPECT_FLOAT_EQ(d.z, 1.0f);
}

TEST(VoxelMean, RunningMeanOfSamples) {
  std::mt19937 rng(42);
  std::normal_distribution<float> noise(0.0f, 0.05f);
  rm_u32 packed = 0;
  rm_u32 count = 0;
  double sx = 0;
  double sy = 0;
  double sz = 0;
  const int n = 500;
  for (int i = 0; i < n; ++i) {
    const rm_vec3f s{0.3f + noise(rng), 0.7f + noise(rng), 0.5f + noise(rng)};
    sx += static_cast<double>(s.x);
    sy += static_cast<double>(s.y);
    sz += static_cast<double>(s.z);
    packed = rm_mean_fold(packed, count, s);
    count = rm_mean_count_increment(count);
  }
  const rm_vec3f m = rm_mean_decode(packed, count);
  EXPECT_EQ(count, static_cast<rm_u32>(n));
  // Re-quantising every update stalls the mean once (sample - mean) / (n + 1) is below half a
  // quantum; with noise of 5 % of a voxel that leaves a few quanta (< 0.5 mm at 0.1 m).
  EXPECT_NEAR(m.x, sx / n, 4.0 / 1023.0);
  EXPECT_NEAR(m.y, sy / n, 4.0 / 1023.0);
  EXPECT_NEAR(m.z, sz / n, 4.0 / 1023.0);
}

TEST(VoxelMean, CountSaturates) { EXPECT_EQ(rm_mean_count_increment(0xFFFFFFFFu), 0xFFFFFFFFu); }

TEST(ScanMark, OncePerScanAndHitsWin) {
  rm_u32 mark = 0;  // cleared voxel
  EXPECT_TRUE(rm_scan_needs_miss(mark, 1));
  mark = rm_scan_mark_miss(1);
  EXPECT_FALSE(rm_scan_needs_miss(mark, 1));  // second miss in scan 1: skipped
  EXPECT_TRUE(rm_scan_needs_hit(mark, 1));    // a hit still applies
  mark = rm_scan_mark_hit(1);
  EXPECT_FALSE(rm_scan_needs_hit(mark, 1));
  EXPECT_FALSE(rm_scan_needs_miss(mark, 1));
  EXPECT_TRUE(rm_scan_needs_miss(mark, 2));  // next scan starts afresh
  EXPECT_TRUE(rm_scan_needs_hit(mark, 2));
  EXPECT_TRUE(rm_scan_needs_miss(rm_scan_mark_hit(RM_SCAN_SEQUENCE_MAX - 1), RM_SCAN_SEQUENCE_MAX));
}

}  // namespace
}  // namespace raymap
