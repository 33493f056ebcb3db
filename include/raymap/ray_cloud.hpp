// SPDX-License-Identifier: BSD-3-Clause
// Reading ray clouds (PLY files with a per-point vector to the sensor, as raycloudtools writes
// them; plain or gzip) and point clouds with a trajectory, one scan at a time, as world rays.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "raymap/error.hpp"
#include "raymap/scan.hpp"
#include <Eigen/Core>

namespace raymap {

/// @brief How a file without per-point origins or scan numbers is read.
struct RayCloudOptions {
  /// Point clouds without per-point origins: a text trajectory `time x y z [qw qx qy qz]` whose
  /// position at each point's time is the sensor's.
  std::string trajectory_path;
  /// The sensor in the trajectory's body frame, metres.
  Eigen::Vector3d sensor_offset = Eigen::Vector3d::Zero();
  /// Files without a `scan` property: a scan is each `scan_period_s` of point time (a value
  /// <= 0 reads the whole file as one scan). Seconds.
  double scan_period_s = 0.1;
};

/// @brief Reads a PLY ray cloud scan by scan (what `raymap populate` reads).
/// Thread-safety: one thread. Not real-time (file I/O).
class RayCloudReader {
 public:
  /// @brief Opens `path` and reads its header. Errors name the file and the reason.
  static Result<RayCloudReader> open(const std::string& path, const RayCloudOptions& options = {});

  RayCloudReader(RayCloudReader&&) noexcept;
  RayCloudReader& operator=(RayCloudReader&&) noexcept;
  ~RayCloudReader();

  /// @brief Reads the next scan (rays with one scan number) into `scan`, replacing what it held.
  /// @return false once the file is exhausted (then `scan` is empty); an error names the file and
  /// what is wrong (a truncated body, a bad value).
  Result<bool> nextScan(std::vector<WorldRay>& scan);
  /// Fraction of the file read so far, 0…1.
  double progress() const noexcept;

 private:
  struct State;
  explicit RayCloudReader(std::unique_ptr<State> state) noexcept;
  std::unique_ptr<State> state_;
};

}  // namespace raymap
