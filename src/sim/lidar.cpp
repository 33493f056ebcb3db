// SPDX-License-Identifier: BSD-3-Clause
// The lidar simulation: sensor paths, column poses and the rays cast through a scene.
#include "src/sim/lidar.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <string>

namespace raymap::sim {
namespace {

/// The angle in [-pi, pi] that differs from `a` by a multiple of 2 pi.
double wrapAngle(double a) noexcept { return std::remainder(a, 2.0 * std::numbers::pi); }

/// A uniform double in [0, 1) from 53 random bits: the same on every standard library.
double uniform01(std::mt19937_64& rng) noexcept {
  return static_cast<double>(rng() >> 11) * 0x1.0p-53;
}

}  // namespace

Result<SensorPath> SensorPath::fromPoses(std::vector<SensorPose> poses) {
  if (poses.empty()) {
    return fail(ErrorCode::kInvalidArgument, "a path needs at least one pose");
  }
  for (std::size_t i = 0; i < poses.size(); ++i) {
    const SensorPose& pose = poses[i];
    if (!std::isfinite(pose.time_s) || !pose.position.isFinite() || !std::isfinite(pose.yaw_rad)) {
      return fail(ErrorCode::kInvalidArgument, "pose " + std::to_string(i) + " is not finite");
    }
    if (i > 0 && !(pose.time_s > poses[i - 1].time_s)) {
      return fail(ErrorCode::kInvalidArgument,
                  "pose " + std::to_string(i) +
                      ": its time does not come after the previous pose's (times must increase "
                      "strictly)");
    }
  }
  return SensorPath(std::move(poses));
}

Result<SensorPath> SensorPath::fromWaypoints(std::span<const Vec3d> waypoints, double speed_mps) {
  if (waypoints.empty()) {
    return fail(ErrorCode::kInvalidArgument, "a path needs at least one waypoint");
  }
  if (!(speed_mps > 0.0) || !std::isfinite(speed_mps)) {
    return fail(ErrorCode::kInvalidArgument, "the speed must be positive");
  }
  for (std::size_t i = 0; i < waypoints.size(); ++i) {
    if (!waypoints[i].isFinite()) {
      return fail(ErrorCode::kInvalidArgument, "waypoint " + std::to_string(i) + " is not finite");
    }
  }
  // Start heading: that of the first segment that moves horizontally.
  double yaw = 0.0;
  for (std::size_t i = 1; i < waypoints.size(); ++i) {
    const Vec3d step = waypoints[i] - waypoints[i - 1];
    if (step.x != 0.0 || step.y != 0.0) {
      yaw = std::atan2(step.y, step.x);
      break;
    }
  }
  std::vector<SensorPose> knots{{0.0, waypoints[0], yaw}};
  for (std::size_t i = 1; i < waypoints.size(); ++i) {
    const Vec3d step = waypoints[i] - waypoints[i - 1];
    const double length = step.norm();
    if (length == 0.0) {
      continue;
    }
    if (step.x != 0.0 || step.y != 0.0) {
      yaw = std::atan2(step.y, step.x);
    }
    if (yaw != knots.back().yaw_rad) {  // turn on the spot at the corner
      knots.push_back({knots.back().time_s, knots.back().position, yaw});
    }
    knots.push_back({knots.back().time_s + length / speed_mps, waypoints[i], yaw});
  }
  return SensorPath(std::move(knots));
}

SensorPose SensorPath::at(double time_s) const noexcept {
  const auto after =
      std::upper_bound(knots_.begin(), knots_.end(), time_s,
                       [](double t, const SensorPose& knot) noexcept { return t < knot.time_s; });
  if (after == knots_.begin() || after == knots_.end()) {
    const SensorPose& rest = after == knots_.begin() ? knots_.front() : knots_.back();
    return {time_s, rest.position, rest.yaw_rad};
  }
  const SensorPose& a = *(after - 1);
  const SensorPose& b = *after;
  const double f = (time_s - a.time_s) / (b.time_s - a.time_s);
  return {time_s, a.position + (b.position - a.position) * f,
          a.yaw_rad + wrapAngle(b.yaw_rad - a.yaw_rad) * f};
}

std::vector<SensorPose> columnPoses(const SimulationConfig& config) {
  const LidarModel& lidar = config.lidar;
  RAYMAP_EXPECTS(lidar.columns >= 1 && lidar.scan_period_s > 0.0 && config.scans >= 0);
  const double start = config.path.startTime();
  const double period = lidar.scan_period_s;
  std::vector<SensorPose> poses;
  poses.reserve(static_cast<std::size_t>(config.scans) * static_cast<std::size_t>(lidar.columns));
  for (int s = 0; s < config.scans; ++s) {
    const SensorPose scan_pose = config.path.at(start + s * period);
    for (int c = 0; c < lidar.columns; ++c) {
      const double time = start + s * period + period * c / lidar.columns;
      SensorPose pose =
          config.sampling == PoseSampling::kPerScan ? scan_pose : config.path.at(time);
      pose.time_s = time;
      poses.push_back(pose);
    }
  }
  return poses;
}

std::vector<Ray> simulateScans(const Scene& scene, const SimulationConfig& config) {
  const LidarModel& lidar = config.lidar;
  RAYMAP_EXPECTS(lidar.beams >= 1);
  const std::vector<SensorPose> poses = columnPoses(config);
  const auto beams = static_cast<std::size_t>(lidar.beams);
  const double deg = std::numbers::pi / 180.0;
  std::vector<double> cos_elevation(beams);
  std::vector<double> sin_elevation(beams);
  for (int b = 0; b < lidar.beams; ++b) {
    const double elevation =
        (lidar.beams > 1
             ? lidar.elevation_min_deg +
                   (lidar.elevation_max_deg - lidar.elevation_min_deg) * b / (lidar.beams - 1)
             : lidar.elevation_min_deg) *
        deg;
    cos_elevation[static_cast<std::size_t>(b)] = std::cos(elevation);
    sin_elevation[static_cast<std::size_t>(b)] = std::sin(elevation);
  }

  std::mt19937_64 rng(config.seed);
  std::normal_distribution<double> noise(0.0,
                                         lidar.range_noise_m > 0.0 ? lidar.range_noise_m : 1.0);
  std::vector<Ray> rays;
  rays.reserve(poses.size() * beams);
  for (std::size_t i = 0; i < poses.size(); ++i) {
    const SensorPose& pose = poses[i];
    const int column = static_cast<int>(i % static_cast<std::size_t>(lidar.columns));
    const double azimuth = pose.yaw_rad + 2.0 * std::numbers::pi * column / lidar.columns;
    const double cos_azimuth = std::cos(azimuth);
    const double sin_azimuth = std::sin(azimuth);
    for (std::size_t b = 0; b < beams; ++b) {
      const Vec3d dir{cos_elevation[b] * cos_azimuth, cos_elevation[b] * sin_azimuth,
                      sin_elevation[b]};
      const double range = castRay(scene, pose.position, dir);
      if (range < lidar.min_range_m) {
        continue;
      }
      Ray ray;
      ray.origin = pose.position;
      ray.time_s = pose.time_s;
      ray.scan = i / static_cast<std::size_t>(lidar.columns);
      if (range > lidar.max_range_m || (lidar.dropout > 0.0 && uniform01(rng) < lidar.dropout)) {
        ray.sample = pose.position + dir * lidar.max_range_m;
        ray.flags = kRayNoReturn;
      } else {
        const double measured = lidar.range_noise_m > 0.0 ? range + noise(rng) : range;
        ray.sample = pose.position + dir * std::max(measured, 0.0);
        ray.intensity = static_cast<float>(100.0 / (1.0 + range));
      }
      rays.push_back(ray);
    }
  }
  return rays;
}

}  // namespace raymap::sim
