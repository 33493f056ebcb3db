// SPDX-License-Identifier: BSD-3-Clause
// What a raymap::Mapper is built from: the map (resolution, semantics, probabilities, memory),
// the rays' limits and the backend. Plain aggregates with the library's defaults.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>

#include "raymap/map_types.hpp"
#include <Eigen/Core>

namespace raymap {

/// @brief NDT-OM and NDT-TM (MapMode::kNdtOm, kNdtTm): each voxel's Gaussian of its samples
/// shapes the misses of rays that pass it. Unset fields take the library's defaults (given
/// here); setting one for a map of another mode is refused, naming it. Keys map.ndt.* in
/// messages (raymapd's YAML names); `raymap populate --ndt-*`.
struct NdtOptions {
  std::optional<double> sensor_noise;  ///< range noise of the sensor (sigma), metres; 0.05
  /// Sigma added on every axis where a Gaussian is inverted, voxel edges, (0, 1]; 0.1.
  std::optional<double> regulariser;
  std::optional<std::uint32_t> sample_threshold;  ///< samples before a Gaussian shapes misses; 4
  /// A voxel whose occupancy probability fell below this restarts its Gaussian at its next hit,
  /// in (0, 0.5); 0.2.
  std::optional<double> reinit_probability;
  std::optional<std::uint32_t> reinit_count;  ///< samples before a Gaussian can restart; 100
  /// How strongly a ray through a surfel lowers its occupancy, [0, 1]; unset: from the miss
  /// probability (clamp(2 (1 - 2 p_miss), 0, 1)).
  std::optional<double> adaptation_rate;
  /// NDT-TM: intensity variance of a voxel after its first sample (intensity units squared); 1.
  std::optional<double> initial_intensity_variance;
};

/// @brief A truncated signed distance field (MapMode::kTsdf). Unset fields take the defaults
/// given here; setting one for a map of another mode is refused. Keys map.tsdf.*; `--tsdf-*`.
struct TsdfOptions {
  std::optional<double> truncation;  ///< tau, metres; 3 voxel edges
  std::optional<double> max_weight;  ///< largest voxel weight (each ray adds at most 1); 10,000
  /// Metres behind the surface where a ray's weight starts to fall; 1 voxel edge; 0: constant.
  std::optional<double> dropoff;
};

/// @brief Maps larger than memory (docs/large-maps.md): past max_memory_bytes the least recently
/// used regions are compressed in memory, and past compressed_memory_bytes spilled to an
/// unnamed file. Off by default in the library (a full pool is then a kCapacity error);
/// `raymap populate` turns them on unless --no-tiers.
struct TierOptions {
  bool enabled = false;
  std::uint64_t compressed_memory_bytes = std::uint64_t{1} << 30;  ///< 1 GiB
  /// Folder of the spill file (it has no name and vanishes with the process); empty: no spill
  /// file, so a full compressed tier is a kCapacity error.
  std::string spill_dir;
};

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
  /// Keep decay rates (reflections per metre of ray path: the traversal layer, 4 bytes a voxel)
  /// beside occupancy or NDT; needs voxel_mean (its sample count is the numerator).
  bool decay_rate = false;
  /// Keep the occupancy layer. false with decay_rate (and kOccupancy, per-ray semantics): a map of
  /// decay rates only, what `raymap populate --mode decay` makes. kTsdf maps have none.
  bool occupancy = true;
  NdtOptions ndt;                  ///< used by kNdtOm and kNdtTm only
  TsdfOptions tsdf;                ///< used by kTsdf only
  double hit_probability = 0.9;    ///< occupancy update of the voxel holding a return
  double miss_probability = 0.45;  ///< update of each voxel a ray crosses before its return
  /// Occupancy is clamped to [min, max] probability (map.clamp_min_probability and
  /// map.clamp_max_probability; OctoMap's 0.1192 and 0.971, -2 and 3.511 in log-odds).
  double clamp_min_probability = 0.11920292202211755;
  double clamp_max_probability = 0.9709991372435236;
  double occupied_threshold = 0.5;  ///< probability at and above which a voxel is occupied
  /// Memory for the map's regions (one preallocated pool); once the map needs more, integration
  /// fails with a capacity error, or with tiers enabled the coldest regions move out. A global
  /// map's pool is never larger than the machine can fill (Mapper::memoryWarning() says so).
  std::uint64_t max_memory_bytes = std::uint64_t{4} << 30;
  TierOptions tiers;
  /// A robot-centric rolling window instead of a map that grows (raymapd's map, `map.window`):
  /// regions per axis (x, y, z; 1 to 4096 each), the pool holding exactly that many, so the
  /// memory is fixed and max_memory_bytes is not used. Mapper::moveWindow() centres it on the
  /// robot; regions that leave it are emptied and recycled, and rays outside it are counted
  /// (rays_out_of_bounds), not integrated. No tiers with a window.
  std::optional<Eigen::Vector3i> window;
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
  /// Device region cache: bytes, or regions when gpu_cache_regions is set (it wins); 0 and 0:
  /// min(1 GiB, half the device memory). Never more regions than max_memory_bytes holds.
  std::uint64_t gpu_cache_bytes = 0;
  std::uint32_t gpu_cache_regions = 0;
  /// Where a device keeps the map while it works: "cache" (device buffers, regions copied in and
  /// out), "shared" (the host map in place: integrated GPUs, PoCL, Jetson) or "auto".
  std::string gpu_memory = "auto";
  /// OpenCL: "span" (a work-item per span record, atomics), "region" (one work-item per region,
  /// right for CPU devices) or "auto" (region on CPU devices).
  std::string opencl_span_work = "auto";
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
