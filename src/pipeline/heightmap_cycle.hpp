// SPDX-License-Identifier: BSD-3-Clause
// One cycle of the periodic task: move the rolling window with the robot, generate the height
// map around it, and account for the latency of the scans it contains.
#pragma once

#include <cstdint>

#include "platform/pi_mutex.hpp"
#include "src/heightmap/heightmap_generator.hpp"
#include "src/heightmap/heightmap_plan.hpp"
#include "src/map/backend.hpp"
#include "src/map/voxel_map.hpp"
#include "src/pipeline/pipeline_stats.hpp"
#include "src/pipeline/pose_update.hpp"

namespace raymap::pipeline {

/// Why a cycle produced no height map.
enum class CycleError : std::uint8_t {
  kNoPose,       ///< no pose received yet: the robot's position is unknown
  kSynchronise,  ///< the device backend failed to make the host map current
  kPlan,         ///< the request does not fit the map (a configuration error caught at start-up)
  kGenerate,     ///< the generator failed
};
const char* toString(CycleError error) noexcept;

/// @brief Generates the robot-centric height map once per call.
///
/// Design: runs on the publisher thread. generate() holds `map_mutex` (shared with the
/// integrator) while it moves the window, plans and generates; a generator that reads the host
/// store (the CPU's, on a device backend only in a CPU fallback) synchronises the backend first,
/// a device generator in the backend's context reads the map where integration left it and only
/// launches its kernels and reads the height map back. Then it notes how many integrated-scan
/// arrivals were queued (all of them are in this map).
/// recordPublished() turns those into latency samples once the map is out.
/// Thread-safety: one thread. @rt generate(): allocates only on the first call (plan and layers
/// reach their fixed size); blocks on map_mutex.
class HeightmapCycle {
 public:
  /// @param options the configured request; its centre is replaced every cycle by the robot's
  /// position (z: minus base_height_m).
  HeightmapCycle(VoxelMap& map, Backend& backend, platform::PiMutex& map_mutex,
                 heightmap::HeightmapGenerator& generator, heightmap::HeightmapOptions options,
                 double base_height_m, const LatestPosition& latest, ArrivalQueue& integrated,
                 PipelineStats& stats);

  /// @brief Generates the height map at the robot's current position.
  Expected<void, CycleError> generate() noexcept;
  /// @brief The map of the last successful generate().
  const heightmap::HeightMap& heightMap() const noexcept { return map_out_; }
  /// @brief header.stamp for that map: the newest scan in it (0 before any).
  std::int64_t dataStampNs() const noexcept { return data_stamp_ns_; }
  /// @brief Records the latency of every scan the last map contained, published at `now_ns`
  /// (monotonic).
  void recordPublished(std::int64_t now_ns) noexcept;

 private:
  VoxelMap& map_;
  Backend& backend_;
  platform::PiMutex& map_mutex_;
  heightmap::HeightmapGenerator& generator_;
  heightmap::HeightmapOptions options_;
  double base_height_m_;
  const LatestPosition& latest_;
  ArrivalQueue& integrated_;
  PipelineStats& stats_;
  heightmap::HeightmapPlan plan_;
  heightmap::HeightMap map_out_;
  std::size_t contained_ = 0;  // arrivals queued when the last map was generated
  std::int64_t data_stamp_ns_ = 0;
};

}  // namespace raymap::pipeline
