// SPDX-License-Identifier: BSD-3-Clause
// A spinning multi-beam lidar moving along a path through a scene: the simulated recording (rays
// in the world frame, deskewed) and the sensor's trajectory.
#pragma once

#include <cstdint>
#include <span>
#include <utility>
#include <vector>

#include "raymap/error.hpp"

#include "src/core/vec3.hpp"
#include "src/map/ray.hpp"
#include "src/sim/scene.hpp"

namespace raymap::sim {

/// @brief Spinning lidar: `beams` rows evenly over [min, max] elevation, `columns` azimuth steps
/// per revolution (counter-clockwise from the sensor's heading), one revolution per scan.
struct LidarModel {
  int beams = 32;
  double elevation_min_deg = -25.0;
  double elevation_max_deg = 15.0;
  int columns = 512;
  double max_range_m = 40.0;    ///< beyond this the lidar reports no return
  double min_range_m = 0.0;     ///< returns nearer than this are not reported at all (blind zone)
  double range_noise_m = 0.01;  ///< standard deviation of Gaussian range noise
  double dropout = 0.0;         ///< probability that a return is reported as a no-return ray
  double scan_period_s = 0.1;   ///< time of one revolution (1 / rate)
};

/// @brief The sensor's pose at a time: position (world frame, metres) and heading (rotation about
/// +z from +x, radians); the sensor stays level.
struct SensorPose {
  double time_s = 0.0;
  Vec3d position;
  double yaw_rad = 0.0;
};

/// @brief A sensor path: poses at increasing times, linear in between (the heading along the
/// shorter arc); before the first pose and after the last the sensor rests there. Immutable.
class SensorPath {
 public:
  /// @brief At rest at the origin, heading +x, from time 0.
  SensorPath() = default;

  /// @brief A path through `poses`. Fails unless there is at least one, every value is finite and
  /// the times increase strictly (the message names the pose by its index).
  static Result<SensorPath> fromPoses(std::vector<SensorPose> poses);

  /// @brief The polyline through `waypoints` driven at constant `speed_mps` from time 0, heading
  /// along the direction of travel (kept through vertical segments). Fails without waypoints, or
  /// with a non-finite waypoint or a speed that is not positive.
  static Result<SensorPath> fromWaypoints(std::span<const Vec3d> waypoints, double speed_mps);

  /// @brief The pose at `time_s` (exactly a knot's pose at its time).
  SensorPose at(double time_s) const noexcept;

  double startTime() const noexcept { return knots_.front().time_s; }
  double endTime() const noexcept { return knots_.back().time_s; }
  /// @brief The poses the path interpolates (a waypoint path repeats a corner's time with the
  /// heading of the next segment).
  std::span<const SensorPose> knots() const noexcept { return knots_; }

 private:
  explicit SensorPath(std::vector<SensorPose> knots) noexcept : knots_(std::move(knots)) {}

  std::vector<SensorPose> knots_{SensorPose{}};  // at least one; times non-decreasing
};

/// @brief Whether the sensor moves during a revolution.
enum class PoseSampling : std::uint8_t {
  kPerColumn,  ///< every column at the path's pose at its own time (a deskewed recording)
  kPerScan,    ///< a whole revolution at the pose of its start time
};

/// @brief What to simulate: scan s covers [start + s T, start + (s + 1) T) with T the scan
/// period and start the path's start time; column c of it fires at start + s T + T c / columns.
struct SimulationConfig {
  LidarModel lidar;
  SensorPath path;
  int scans = 10;
  std::uint64_t seed = 1;
  PoseSampling sampling = PoseSampling::kPerColumn;
};

/// @brief The sensor pose of every column of every scan, in time order (scans x columns poses):
/// the trajectory of the recording simulateScans() makes.
/// @pre config.lidar.columns >= 1, scan_period_s > 0, scans >= 0
std::vector<SensorPose> columnPoses(const SimulationConfig& config);

/// @brief Simulates the scans: for each column, each beam from bottom to top, one ray from the
/// sensor position to the first surface, with Gaussian range noise, time, scan index and an
/// intensity falling with range (100 / (1 + range)). Rays that meet nothing within max range,
/// and returns lost to dropout, are no-return rays (kRayNoReturn) ending at max range; returns
/// nearer than min range are left out. Deterministic for a given seed (std::mt19937_64; the
/// normal distribution is libstdc++'s, so another standard library gives other noise).
/// @pre config.lidar.beams >= 1, columns >= 1, scan_period_s > 0, scans >= 0
std::vector<Ray> simulateScans(const Scene& scene, const SimulationConfig& config);

}  // namespace raymap::sim
