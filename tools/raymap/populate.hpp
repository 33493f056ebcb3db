// SPDX-License-Identifier: BSD-3-Clause
// The offline mapping job: stream rays from a file through preparation into a backend.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

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
#include "tools/raymap/json_output.hpp"
#include "tools/raymap/memory_tiers.hpp"

namespace raymap::cli {

// Backend creation is shared with raymapd (src/device/backend_choice.hpp).
using backends::availableBackends;
using backends::BackendChoice;
using backends::createBackend;
using backends::CreatedBackend;
using backends::CreatedHeightmapGenerator;
using backends::createHeightmapGenerator;

/// @brief Everything `raymap populate` needs besides output paths.
struct PopulateOptions {
  std::string input;
  RecordingOptions recording;  ///< how the input is read (a PLY, or a rosbag2 bag)
  MapConfig map;
  RayFilter filter;
  BackendChoice backend;       ///< backend, CPU threads, device options
  std::size_t batch_rays = 0;  ///< prepared rays per backend call; 0: the backend's preference
  bool progress = true;        ///< progress bar on a terminal
};

/// @brief What a run did and how long it took.
struct PopulateReport {
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

/// @brief What integrateStream keeps from one call to the next when asked to (`bench
/// --steady-state`, height-map cycles): the backend, so that a device's cache stays warm, and the
/// batcher, so that its batch of prepared rays stays resident, as in a service that runs for
/// hours. Made on first use.
struct StreamState {
  CreatedBackend created;
  std::unique_ptr<RayBatcher> batcher;
};

/// @brief Integrates rays into `map` with a new backend, batching by size (per-ray) or by scan
/// (per-scan). `next_chunk` fills a span and returns how many rays it wrote (0 at the end).
/// `progress` gets the fraction of the input consumed. Fails on read errors and when a global
/// map's store is full (the message says how to raise --max-memory).
/// `reuse`: when given, the backend and the batcher are taken from it (made there on first use)
/// and kept for the next call; the report's backend and scan counters then cover this call only.
Result<PopulateReport> integrateStream(
    VoxelMap& map, const PopulateOptions& options,
    const std::function<Result<std::size_t>(std::span<Ray>)>& next_chunk,
    const std::function<double()>& progress, StreamState* reuse = nullptr);

/// @brief Opens options.input and integrates it (integrateStream over a RaySource); records
/// provenance in the map's info.
Result<PopulateReport> populateFromFile(VoxelMap& map, const PopulateOptions& options);

/// @brief The warning for an input that lacks what the map mode uses (empty when none): NDT-TM
/// maps keep intensity statistics, and a file without an `intensity` property gives 0 for all.
std::string inputWarning(MapMode mode, const io::RaySourceInfo& input);

/// @brief The statistics JSON of a run (keys documented in docs/cli.md).
Json statsJson(const PopulateReport& report, const PopulateOptions& options);

}  // namespace raymap::cli
