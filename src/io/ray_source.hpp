// SPDX-License-Identifier: BSD-3-Clause
// Streamed sources of rays from files: ray-cloud PLY, or point-cloud PLY plus a trajectory.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <string>

#include "raymap/error.hpp"

#include "src/core/vec3.hpp"
#include "src/map/ray.hpp"

namespace raymap::io {

/// @brief How to turn a file into rays.
struct RaySourceOptions {
  static constexpr double kDefaultScanPeriod = 0.1;  // seconds (a 10 Hz lidar)

  /// Point clouds without per-point origins: text trajectory `time x y z [qw qx qy qz]`.
  std::string trajectory_path;
  /// Sensor position in the trajectory's body frame, metres; rotated by the trajectory orientation
  /// when the trajectory has one, added as is otherwise.
  Vec3d sensor_offset{};
  /// Files without a `scan` property: scan index = floor((time - first time) / period). A value
  /// <= 0 puts the whole file in one scan.
  double scan_period_s = kDefaultScanPeriod;
};

/// @brief What the source found in the file header.
struct RaySourceInfo {
  std::string path;
  std::string format;               ///< "ascii", "binary_little_endian" or "binary_big_endian"
  bool compressed = false;          ///< gzip-compressed (.ply.gz)
  bool ray_cloud = false;           ///< per-point vector to the sensor (origin = point + normal)
  std::uint64_t declared_rays = 0;  ///< vertex count from the header
  std::string time_property;        ///< property used as time, empty when none
  bool has_scan = false;            ///< `scan` property present
  bool has_intensity = false;
  bool has_alpha = false;  ///< alpha present (0 = no-return ray)
};

/// @brief A stream of rays in file order. Reads a bounded chunk at a time, so files larger than
/// memory work. Errors name the file and the problem (line or vertex number where it helps).
/// Not thread-safe; one reader per source.
class RaySource {
 public:
  virtual ~RaySource() = default;
  /// @brief Fills up to out.size() rays; returns how many, 0 at the end of the data.
  virtual Result<std::size_t> read(std::span<Ray> out) = 0;
  virtual const RaySourceInfo& info() const noexcept = 0;
  /// @brief Fraction of the file consumed so far, 0 to 1 (of the compressed bytes for .gz).
  virtual double progress() const noexcept = 0;
};

/// @brief Opens a PLY (binary little/big endian or ASCII, optionally gzip-compressed) as a ray
/// source. With normals (nx/ny/nz or normal_x/y/z) it is a ray cloud, and a
/// options.trajectory_path is refused (kInvalidArgument: it would not be used); otherwise
/// options.trajectory_path is required.
Result<std::unique_ptr<RaySource>> openRaySource(const std::string& path,
                                                 const RaySourceOptions& options);

}  // namespace raymap::io
