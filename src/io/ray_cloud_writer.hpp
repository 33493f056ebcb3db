// SPDX-License-Identifier: BSD-3-Clause
// Writing rays as a ray-cloud PLY (the raycloudtools convention raymap and OHM read).
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <string>

#include "src/core/error.hpp"
#include "src/map/ray.hpp"

namespace raymap::io {

/// @brief Streams rays into a binary little-endian ray-cloud PLY with the layout of the shared
/// data: double x y z (sample, world frame, metres), double time (s), float nx ny nz
/// (origin - sample), float intensity, uint scan, uchar alpha (255 = return, 0 = no-return ray).
/// The vertex count is patched in on finish(); the file appears (temporary file + rename) only
/// then. Not thread-safe.
class RayCloudWriter {
 public:
  static Result<std::unique_ptr<RayCloudWriter>> open(const std::string& path);
  virtual ~RayCloudWriter() = default;
  virtual Expected<void, Error> write(std::span<const Ray> rays) = 0;
  virtual Expected<void, Error> finish() = 0;
  virtual std::uint64_t count() const noexcept = 0;
};

}  // namespace raymap::io
