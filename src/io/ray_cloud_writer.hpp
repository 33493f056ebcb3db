// SPDX-License-Identifier: BSD-3-Clause
// Writing rays as a ray-cloud PLY (the raycloudtools convention raymap and OHM read).
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <string>

#include "raymap/error.hpp"

#include "src/map/ray.hpp"

namespace raymap::io {

/// @brief What a RayCloudWriter writes for each ray.
enum class PlyLayout : std::uint8_t {
  /// Every ray: double x y z (sample), double time, float nx ny nz (origin - sample), float
  /// intensity, uint scan, uchar alpha (255 = return, 0 = no-return ray).
  kRayCloud,
  /// Returns only (no-return rays are skipped, a point cloud cannot hold them): double x y z,
  /// double time, float intensity, uint scan. `raymap populate` reads it with a trajectory.
  kPointCloud,
};

/// @brief Streams rays into a binary little-endian PLY, world frame, metres: a ray cloud with the
/// layout of the shared data, or a point cloud (PlyLayout). The vertex count is patched in on
/// finish(); the file appears (temporary file + rename) only then. Not thread-safe.
class RayCloudWriter {
 public:
  static Result<std::unique_ptr<RayCloudWriter>> open(const std::string& path,
                                                      PlyLayout layout = PlyLayout::kRayCloud);
  virtual ~RayCloudWriter() = default;
  virtual Expected<void, Error> write(std::span<const Ray> rays) = 0;
  virtual Expected<void, Error> finish() = 0;
  /// @brief Vertices written so far.
  virtual std::uint64_t count() const noexcept = 0;
};

}  // namespace raymap::io
