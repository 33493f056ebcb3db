// SPDX-License-Identifier: BSD-3-Clause
// The offline mapping job: rays from a reader, through preparation and batching, into a backend,
// timed and counted. `raymap populate`, `raymap bench` and `raymap demo` are front ends over it;
// a program that maps recordings links it (raymap::raymap) and gets the same map and report.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>

#include "raymap/error.hpp"
#include "raymap/recording.hpp"

#include "src/bag/bag_ray_source.hpp"
#include "src/device/backend_choice.hpp"
#include "src/io/ray_source.hpp"
#include "src/map/backend.hpp"
#include "src/map/decay_summary.hpp"
#include "src/map/ray_batcher.hpp"
#include "src/map/ray_preparer.hpp"
#include "src/map/tsdf_surface.hpp"
#include "src/map/voxel_map.hpp"
#include "src/mapper/tier_report.hpp"

namespace raymap::mapper {

/// @brief How rays are prepared and integrated. Value type.
struct IntegrationOptions {
  RayFilter filter;
  backends::BackendChoice backend;  ///< backend, CPU threads, device options
  std::size_t batch_rays = 0;       ///< prepared rays per backend call; 0: the backend's preference
};

/// @brief Where a run is, after each chunk of rays. Value type.
struct IntegrationProgress {
  double fraction = 0;         ///< of the input consumed, 0..1
  std::uint64_t rays_in = 0;   ///< rays read so far
  double rays_per_second = 0;  ///< accepted rays per second of integration so far
};

/// @brief Called on the integrating thread after each chunk; must not throw.
using ProgressCallback = std::function<void(const IntegrationProgress&)>;

/// @brief What a run did and how long it took. Value type; times in seconds (steady clock).
struct IntegrationReport {
  RayCounters rays;
  BackendStats backend;
  std::string backend_name;
  std::string device;            ///< device backends: the device in words
  std::string fallback_warning;  ///< the requested device failed; the CPU mapped instead
  std::string startup_warning;   ///< a non-fatal start-up problem of the backend
  std::string input_warning;     ///< the input lacks something the map uses (NDT-TM intensity)
  unsigned threads = 0;
  std::uint64_t scans = 0;        ///< runs of equal scan index seen
  std::uint64_t scans_split = 0;  ///< per-scan: scans larger than a batch, integrated in parts
  double integrate_seconds = 0;   ///< preparation + integration + final device sync; no reading
  /// CPU seconds over the same span as integrate_seconds: the whole process (every thread: a
  /// CPU backend's workers, PoCL's device threads) and the thread that prepares and plans.
  double integrate_cpu_seconds = 0;
  double integrate_thread_cpu_seconds = 0;
  double read_seconds = 0;                ///< reading and decoding the input
  std::optional<bag::BagRaysReport> bag;  ///< rosbag2 input: what its messages gave
  double total_seconds = 0;
  MapSummary summary;
  TsdfSummary tsdf;    ///< TSDF maps (zero otherwise)
  DecaySummary decay;  ///< maps with decay rates (zero otherwise)
  std::uint64_t peak_rss_bytes = 0;
  std::optional<TierReport> tiers;  ///< maps with cold tiers (after the compressor drained)
};

/// @brief What integrateRays keeps from one call to the next when asked to (a benchmark's steady
/// state, height-map cycles): the backend, so that a device's cache stays warm, and the batcher,
/// so that its batch of prepared rays stays resident, as in a service that runs for hours. Made
/// on first use. Not thread-safe: one job at a time.
struct IntegrationSession {
  backends::CreatedBackend created;
  std::unique_ptr<RayBatcher> batcher;
};

/// @brief Fills a span with the next rays and returns how many it wrote (0 at the end).
using RayChunkReader = std::function<Result<std::size_t>(std::span<Ray>)>;

/// @brief Integrates rays into `map` with a new backend, batching by size (per-ray) or by scan
/// (per-scan). `fraction` tells how much of the input is consumed (for `on_progress`, which may
/// be empty). Fails on read errors and when a global map's store is full (the message names
/// map.max_memory). `reuse`: when given, the backend and the batcher are taken from it (made
/// there on first use) and kept for the next call; the report's backend and scan counters then
/// cover this call only. Drains the map's tiers at the end and fails if they lost a region.
Result<IntegrationReport> integrateRays(VoxelMap& map, const IntegrationOptions& options,
                                        const RayChunkReader& next_chunk,
                                        const std::function<double()>& fraction,
                                        const ProgressCallback& on_progress,
                                        IntegrationSession* reuse = nullptr);

/// @brief Opens `input` as RecordingReader does (a PLY ray cloud, a point cloud with a
/// trajectory, or a rosbag2 bag), integrates it (integrateRays) and records provenance in the
/// map's info: source, ray counts, the filter and `created_by`.
Result<IntegrationReport> integrateRecording(VoxelMap& map, const std::string& input,
                                             const RecordingOptions& recording,
                                             const IntegrationOptions& options,
                                             const ProgressCallback& on_progress,
                                             std::string_view created_by);

/// @brief The warning for an input that lacks what the map mode uses (empty when none): NDT-TM
/// maps keep intensity statistics, and a file without an `intensity` property gives 0 for all.
std::string inputWarning(MapMode mode, const io::RaySourceInfo& input);

/// @brief Counters of `now` minus those of `before` (a reused backend's share of one run).
BackendStats statsSince(const BackendStats& now, const BackendStats& before);

}  // namespace raymap::mapper
