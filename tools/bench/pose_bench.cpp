// SPDX-License-Identifier: BSD-3-Clause
// Google Benchmark micro-benchmarks of the host-side pose maths on the hot paths: deskewing one
// lidar scan (PointDeskewer::toRay: a pose lookup, interpolation and composition per distinct
// point time, a transform per point) and the PLY ray source's per-ray trajectory interpolation
// (io::Trajectory::poseAt, then the sensor offset transformed).
// Run: build/release/tools/raymap-pose-bench --benchmark_format=json
#include <cmath>
#include <cstdint>
#include <numbers>
#include <optional>
#include <vector>

#include <benchmark/benchmark.h>

#include "src/core/eigen_conversions.hpp"
#include "src/io/trajectory.hpp"
#include "src/pipeline/deskew.hpp"
#include "src/pipeline/pose_history.hpp"

namespace raymap {
namespace {

// One scan of an Ouster OS1-64 in 1024x10 mode: 1024 columns (distinct point times) of 64 beams.
constexpr int kColumns = 1024;
constexpr int kBeams = 64;
constexpr double kScanPeriodS = 0.1;
constexpr std::int64_t kStampNs = 1700000000000000000;  // header.stamp of the scan
constexpr std::int64_t kPosePeriodNs = 10000000;        // odometry at 100 Hz

/// The base at time t (seconds after the stamp) on a curve: 2 m/s forward, turning at 0.5 rad/s,
/// rolling a little (world frame, metres).
io::Pose basePose(double t_s) {
  const double yaw = 0.5 * t_s;
  const double roll = 0.05 * std::sin(3.0 * t_s);
  io::Pose pose;
  pose.position = {4.0 * std::sin(yaw), 4.0 * (1.0 - std::cos(yaw)), 0.3 + 0.01 * t_s};
  pose.orientation = Eigen::Quaterniond(Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ())) *
                     Eigen::Quaterniond(Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()));
  return pose;
}

/// The lidar on the base: 0.3 m ahead, 1.2 m up, turned half round about z (base frame).
io::Pose extrinsic() {
  io::Pose pose;
  pose.position = {0.3, 0.0, 1.2};
  pose.orientation = Eigen::Quaterniond(0.0, 0.0, 0.0, 1.0);  // w x y z
  return pose;
}

/// The scan's points in the sensor frame (metres), ranges 5 to 30 m. Column-major (a column's
/// beams together: 1024 pose lookups per scan) or row-major as Ouster drivers publish them (each
/// point's time differs from the previous one's: a lookup per point).
std::vector<msgs::ScanPoint> scanPoints(bool row_major) {
  std::vector<msgs::ScanPoint> points;
  points.reserve(std::size_t{kColumns} * kBeams);
  const auto add = [&](int column, int beam) {
    const double azimuth = 2.0 * std::numbers::pi * column / kColumns;
    const double elevation = (-22.5 + 45.0 * beam / (kBeams - 1)) * std::numbers::pi / 180.0;
    const double range = 5.0 + 25.0 * ((column * 7 + beam * 13) % 101) / 100.0;
    points.push_back({static_cast<float>(range * std::cos(elevation) * std::cos(azimuth)),
                      static_cast<float>(range * std::cos(elevation) * std::sin(azimuth)),
                      static_cast<float>(range * std::sin(elevation)),
                      static_cast<float>(kScanPeriodS * column / kColumns), 100.0f, 0u});
  };
  if (row_major) {
    for (int beam = 0; beam < kBeams; ++beam) {
      for (int column = 0; column < kColumns; ++column) {
        add(column, beam);
      }
    }
  } else {
    for (int column = 0; column < kColumns; ++column) {
      for (int beam = 0; beam < kBeams; ++beam) {
        add(column, beam);
      }
    }
  }
  return points;
}

void BM_DeskewScan(benchmark::State& state) {
  const bool row_major = state.range(0) != 0;
  pipeline::PoseHistory history(64);
  for (std::int64_t t = -2 * kPosePeriodNs; t <= 12 * kPosePeriodNs; t += kPosePeriodNs) {
    history.push(kStampNs + t, basePose(static_cast<double>(t) * 1e-9));
  }
  const io::Pose sensor_in_base = extrinsic();
  const std::vector<msgs::ScanPoint> points = scanPoints(row_major);
  std::vector<Ray> rays(points.size());
  pipeline::PointDeskewer deskewer;
  for (auto _ : state) {
    deskewer.reset();
    for (std::size_t i = 0; i < points.size(); ++i) {
      if (!deskewer.toRay(points[i], kStampNs, history, 0, sensor_in_base, 0, rays[i])) {
        state.SkipWithError("no pose");
        return;
      }
    }
    benchmark::DoNotOptimize(rays.data());
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(points.size()));
}
BENCHMARK(BM_DeskewScan)->ArgName("row_major")->Arg(0)->Arg(1);

/// The PLY ray source's work per ray of a point cloud with a trajectory: the pose at the ray's
/// time (time-ordered, with the segment hint), then the sensor offset into the world frame.
void BM_TrajectoryRayOrigins(benchmark::State& state) {
  std::vector<io::TrajectorySample> samples;
  for (int k = 0; k <= 100; ++k) {  // 100 Hz over one second
    const double t = 0.01 * k;
    const io::Pose pose = basePose(t);
    samples.push_back({t, pose.position, pose.orientation});
  }
  const auto trajectory = io::Trajectory::fromSamples(std::move(samples), true, "bench");
  if (!trajectory) {
    state.SkipWithError("no trajectory");
    return;
  }
  std::vector<double> times;  // one scan's rays: 1024 distinct times, 64 rays each
  for (int column = 0; column < kColumns; ++column) {
    for (int beam = 0; beam < kBeams; ++beam) {
      times.push_back(0.25 + kScanPeriodS * column / kColumns);
    }
  }
  const Vec3d sensor_offset{0.3, 0.0, 1.2};  // body frame, metres
  std::vector<Vec3d> origins(times.size());
  for (auto _ : state) {
    std::size_t hint = 0;
    for (std::size_t i = 0; i < times.size(); ++i) {
      const std::optional<io::Pose> pose = trajectory->poseAt(times[i], hint);
      origins[i] = toVec3(pose->transform(toEigen(sensor_offset)));
    }
    benchmark::DoNotOptimize(origins.data());
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(times.size()));
}
BENCHMARK(BM_TrajectoryRayOrigins);

}  // namespace
}  // namespace raymap

BENCHMARK_MAIN();
