// SPDX-License-Identifier: BSD-3-Clause
// Deskewing from a batch's tables (kernels/common/deskew.h: what the device runs, and the host
// where it converts points itself) against pipeline::PointDeskewer on the PoseHistory the tables
// were copied from: the same rays, bit for bit, for points anywhere in the covered range, at
// sample times, before the oldest's successor and after the newest pose (held).
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "kernels/common/deskew.h"
#include "src/pipeline/deskew.hpp"
#include "src/pipeline/pose_history.hpp"

namespace raymap::pipeline {
namespace {

io::Pose deskewTablesPose(std::mt19937_64& rng, double spread) {
  std::uniform_real_distribution<double> u(-spread, spread);
  std::normal_distribution<double> n(0.0, 1.0);
  return io::Pose{Eigen::Vector3d(u(rng), u(rng), u(rng)),
                  Eigen::Quaterniond(n(rng), n(rng), n(rng), n(rng)).normalized()};
}

TEST(DeskewTables, GiveThePointDeskewersRaysBitForBit) {
  std::mt19937_64 rng(3);
  PoseHistory history(64);
  constexpr std::int64_t kStep = 10'000'000;  // 100 Hz odometry
  for (int k = 0; k < 100; ++k) {             // the ring keeps the newest 64
    (void)history.push(1'000'000'000 + k * kStep + (k % 3) * 1000, deskewTablesPose(rng, 20.0));
  }
  const io::Pose extrinsic = deskewTablesPose(rng, 1.0);
  const std::int64_t stamp = history.newestStamp() - 30 * kStep;
  const std::int64_t hold = 5 * kStep;
  // A scan of 0.1 s around the stamp, and points up to the hold past the newest pose.
  std::uniform_real_distribution<float> offset(-0.05f, 0.35f);
  std::uniform_real_distribution<float> coordinate(-40.0f, 40.0f);
  std::vector<msgs::ScanPoint> points;
  for (int i = 0; i < 5000; ++i) {
    points.push_back(msgs::ScanPoint{coordinate(rng), coordinate(rng), coordinate(rng),
                                     i % 50 == 0 ? 0.0f : offset(rng), 7.0f,
                                     i % 17 == 0 ? msgs::kPointFreeOnly : 0u});
  }
  points.push_back(
      msgs::ScanPoint{1.0f, 2.0f, 3.0f,
                      static_cast<float>(static_cast<double>(history.newestStamp() - stamp) * 1e-9),
                      0.0f, 0});  // exactly at the newest pose
  const ScanTimes times = scanTimes(points, stamp, 1.0f);
  std::vector<rm_pose_sample> samples(64);
  const std::size_t n = history.copyCovering(times.start_ns, times.end_ns, samples);
  ASSERT_GT(n, 2u);
  const rm_deskew_segment segment{io::toRmPose(extrinsic), 0, static_cast<rm_u32>(n)};
  PointDeskewer deskewer;
  std::size_t compared = 0;
  for (const msgs::ScanPoint& p : points) {
    Ray ray;
    if (!deskewer.toRay(p, stamp, history, hold, extrinsic, 0, ray)) {
      continue;  // past the hold: not covered
    }
    const rm_scan_point q{p.x, p.y, p.z, p.intensity, 0, 0, pointTimeNs(stamp, p.time_s)};
    rm_vec3d origin;
    rm_vec3d sample;
    rm_deskew_point(q, samples.data(), segment, &origin, &sample);
    ASSERT_EQ(origin.x, ray.origin.x) << compared;
    ASSERT_EQ(origin.y, ray.origin.y) << compared;
    ASSERT_EQ(origin.z, ray.origin.z) << compared;
    ASSERT_EQ(sample.x, ray.sample.x) << compared;
    ASSERT_EQ(sample.y, ray.sample.y) << compared;
    ASSERT_EQ(sample.z, ray.sample.z) << compared;
    ++compared;
  }
  EXPECT_GT(compared, 4000u);
}

TEST(DeskewTables, CoverExactlyTheBracketsOfTheirRange) {
  PoseHistory history(8);
  for (int k = 0; k < 8; ++k) {
    (void)history.push(100 * k, io::Pose{});
  }
  std::vector<rm_pose_sample> out(8);
  ASSERT_EQ(history.copyCovering(150, 320, out), 4u);  // 100, 200, 300, 400
  EXPECT_EQ(out[0].time_ns, 100);
  EXPECT_EQ(out[3].time_ns, 400);
  ASSERT_EQ(history.copyCovering(300, 300, out), 2u);  // 300, 400
  EXPECT_EQ(out[0].time_ns, 300);
  ASSERT_EQ(history.copyCovering(650, 900, out), 2u);  // 600, 700 (newest, held past it)
  EXPECT_EQ(out[1].time_ns, 700);
  std::vector<rm_pose_sample> small(2);
  EXPECT_EQ(history.copyCovering(0, 700, small), 0u);  // does not fit
  EXPECT_EQ(PoseHistory(4).copyCovering(0, 10, out), 0u);
}

}  // namespace
}  // namespace raymap::pipeline
