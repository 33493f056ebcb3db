// SPDX-License-Identifier: BSD-3-Clause
// What a raymap::Mapper is built from: the map (resolution, semantics, probabilities, memory),
// the rays' limits and the backend. Plain aggregates with the library's defaults.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

#include "raymap/map_types.hpp"

namespace raymap {

/// @brief The map: geometry, how rays combine, the occupancy model and the memory it may use.
/// Defaults are OctoMap's probabilities at 0.1 m, as `raymap populate` uses them.
struct MapOptions {
  double resolution = 0.1;          ///< voxel edge, metres
  std::int32_t region_voxels = 32;  ///< voxels per region edge (4…128); regions are allocated whole
  Semantics semantics = Semantics::kPerRay;
  /// kOccupancy, kNdtOm or kNdtTm (NDT needs per-ray semantics), or kTsdf (a distance field:
  /// no occupancy layer, so occupancy queries answer "unobserved" and height maps are refused).
  MapMode mode = MapMode::kOccupancy;
  bool voxel_mean = true;  ///< keep each voxel's mean sample position (sub-voxel surface heights)
  double hit_probability = 0.9;      ///< occupancy update of the voxel holding a return
  double miss_probability = 0.45;    ///< update of each voxel a ray crosses before its return
  float clamp_min_log_odds = -2.0f;  ///< occupancy is clamped to [min, max] (log-odds)
  float clamp_max_log_odds = 3.511f;
  double occupied_threshold = 0.5;  ///< probability at and above which a voxel is occupied
  /// Memory for the map's regions (one preallocated pool); integration fails with a capacity
  /// error once the map needs more.
  std::uint64_t max_memory_bytes = std::uint64_t{4} << 30;
};

/// @brief Limits applied to every ray before it is integrated (invalid rays are counted, never
/// fatal).
struct RayOptions {
  double min_range = 0.0;  ///< metres; shorter rays are dropped (returns from the robot itself)
  double max_range = 0.0;  ///< metres; 0 = none; longer rays clear free space to it, no hit
  /// Metres; 0 = none. Longer rays are outlier returns: rejected (counted in
  /// MapperCounters::rays_out_of_bounds), never clipped, so one ghost return kilometres away
  /// cannot grow the map by thousands of regions.
  double max_ray_length = 1000.0;
  double segment_length = 0.0;  ///< metres; 0 = off, else long rays are cut into pieces
  /// Walk each ray from its sample back to the origin (spreads contention on a GPU; the same
  /// voxels either way). Unset (the default) means: forward on the CPU, reverse on a device.
  enum class Walk : std::uint8_t { kAuto, kForward, kReverse } walk = Walk::kAuto;
};

/// @brief Where integration runs.
struct BackendOptions {
  std::string name = "cpu";     ///< "cpu", "opencl" or "cuda" (what the build has)
  unsigned threads = 0;         ///< CPU: worker threads, 0 = all cores, 1 = the serial reference
  std::string opencl_platform;  ///< index or name substring; empty = default
  std::string opencl_device;    ///< index or name substring; empty = first GPU, else first device
  int cuda_device = 0;          ///< CUDA device ordinal
  /// Use the CPU backend (MapperCounters::fallback_warning says why) if the device cannot start.
  bool fallback_cpu = false;
  /// OpenCL and CUDA: where each batch is planned (its rays' regions, span records, hit groups),
  /// "host" or "device" (the host only places each batch's distinct regions; the same map).
  std::string device_planning = "host";
  /// Prepared rays per backend call; 0 = the backend's preference (32,768 on the CPU for per-ray
  /// maps other than NDT; 262,144 for per-scan and NDT maps and on a device).
  std::size_t batch_rays = 0;
};

/// @brief Everything raymap::Mapper::create() needs.
struct MapperConfig {
  MapOptions map;
  RayOptions rays;
  BackendOptions backend;
};

}  // namespace raymap
