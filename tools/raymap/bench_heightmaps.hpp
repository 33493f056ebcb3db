// SPDX-License-Identifier: BSD-3-Clause
// `raymap bench --heightmap-every`: raymapd's height-map cycle between integration batches, so
// that what a cycle costs (copies, waiting, generation) is measured without DDS.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "raymap/error.hpp"

#include "src/device/backend_choice.hpp"
#include "src/heightmap/heightmap_generator.hpp"
#include "src/heightmap/heightmap_plan.hpp"
#include "src/map/backend.hpp"
#include "src/map/voxel_map.hpp"
#include "tools/raymap/json_output.hpp"

namespace raymap::cli {

/// @brief How the benchmark generates height maps.
struct BenchHeightmapOptions {
  std::uint64_t every_rays = 0;  ///< a height map each time this many more rays were read; 0: off
  double size_m = 20.0;          ///< side of the planar map, metres
  /// Read the host store as before issue 24 (synchronise, then a generator with its own device
  /// context) instead of the layers where the device backend left them.
  bool from_host = false;
};

/// @brief Runs height-map cycles on one map and backend and keeps their costs.
/// Thread-safety: one thread, the one that integrates (cycles run between batches).
class BenchHeightmaps {
 public:
  explicit BenchHeightmaps(const BenchHeightmapOptions& options) : options_(options) {}

  bool enabled() const noexcept { return options_.every_rays > 0; }
  /// @brief Generates a height map around `sensor` (world frame, metres; z is the reference
  /// height) if `rays_read` has passed the next multiple of every_rays. The generator is created
  /// on first use, over `backend` (or, from_host, standalone for `choice`).
  Expected<void, Error> maybeGenerate(std::uint64_t rays_read, Vec3d sensor, VoxelMap& map,
                                      Backend& backend, const backends::BackendChoice& choice);
  /// @brief The costs as a JSON object (keys documented in docs/cli.md), with the run's
  /// `rays` and integration seconds for the combined rate.
  Json json(std::uint64_t rays, double integrate_seconds) const;
  double seconds() const noexcept { return seconds_; }

 private:
  BenchHeightmapOptions options_;
  std::unique_ptr<heightmap::HeightmapGenerator> generator_;
  heightmap::HeightmapPlan plan_;
  heightmap::HeightMap out_;
  std::uint64_t next_at_ = 0;
  std::uint64_t skipped_ = 0;  // centre outside the stored regions
  double seconds_ = 0;
  std::vector<double> generate_ms_;
  std::vector<double> sync_bytes_;
  std::vector<double> copy_bytes_;      // the map's layers
  std::vector<double> transfer_bytes_;  // everything, tables and read-back included
};

}  // namespace raymap::cli
