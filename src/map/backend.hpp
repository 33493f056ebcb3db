// SPDX-License-Identifier: BSD-3-Clause
// The interface every integration backend (CPU, OpenCL, CUDA) implements.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>

#include "raymap/expected.hpp"

#include "kernels/common/deskew.h"
#include "src/map/ray.hpp"

namespace raymap {

class RayPreparer;
struct RayFilter;
struct RayCounters;

/// @brief What deskewing a batch of points (rm_scan_point) needs besides the points: the base
/// pose samples and the segments of kernels/common/deskew.h, and the scan (Ray::scan) of each
/// segment. Views; the caller owns the tables.
struct DeskewTables {
  std::span<const rm_pose_sample> poses;
  std::span<const rm_deskew_segment> segments;
  std::span<const std::uint64_t> segment_scans;
};

/// @brief The world-frame Ray of point `p` deskewed with `tables` (kernels/common/deskew.h): what
/// a device makes of it, made on the host. @rt allocates: no.
Ray deskewedRay(const rm_scan_point& p, const DeskewTables& tables) noexcept;

/// Why a batch could not be integrated (real-time path: a code, no message).
enum class IntegrateError : std::uint8_t {
  kStoreFull,      ///< a global map's region pool is exhausted; the batch is not (fully) integrated
  kDeviceFailure,  ///< the device reported an error
  kTierFailed,     ///< a global map's cold tiers failed (VoxelMap::tierFailure() says why)
  kOutOfMemory,    ///< the host refused scratch memory for a batch larger than any before
};

const char* toString(IntegrateError error) noexcept;

/// @brief Counters a backend keeps over its lifetime.
struct BackendStats {
  std::uint64_t batches = 0;
  std::uint64_t rays = 0;             ///< prepared rays integrated
  std::uint64_t voxels_visited = 0;   ///< voxel visits (updates plus skipped per-scan repeats)
  std::uint64_t updates_dropped = 0;  ///< updates given up under contention (always 0 on the CPU)
  std::uint64_t spans_outside_window = 0;  ///< ray pieces skipped: region outside a rolling window
  /// Batches cut in two because their regions did not fit a tiered map's pool at once (CPU).
  std::uint64_t batches_split = 0;
  // ---- device backends (0 on the CPU) ----
  std::uint64_t rays_skipped = 0;       ///< rays crossing more regions than the device cache holds
  std::uint64_t bytes_to_device = 0;    ///< batch arrays and region uploads
  std::uint64_t bytes_from_device = 0;  ///< region downloads and counters
  std::uint64_t region_bytes_to_device = 0;    ///< of bytes_to_device: region uploads only
  std::uint64_t region_bytes_from_device = 0;  ///< of bytes_from_device: region downloads only
  std::uint64_t cache_hits = 0;                ///< a batch needed a region already on the device
  std::uint64_t cache_misses = 0;              ///< it had to be uploaded or created there
  std::uint64_t cache_evictions = 0;           ///< a region left the device to make room
  /// Region moves that waited for the device because the staging ring was full (device caches;
  /// 0 in a steady state that fits the ring).
  std::uint64_t transfer_stalls = 0;
  std::uint64_t cache_slots = 0;    ///< regions the device cache holds
  bool planned_on_device = false;   ///< batches are planned on the device (DevicePlanner)
  std::uint64_t plans_on_host = 0;  ///< planning on the device: batches the host planned instead
  /// Rays prepared on the device (Backend::integrateRays; the rest, if any, on the host).
  std::uint64_t rays_prepared_on_device = 0;
  /// Of them, points the device deskewed first (Backend::integratePoints).
  std::uint64_t points_deskewed_on_device = 0;
  double plan_seconds = 0;  ///< host: region walk, region moves, hit grouping (device planning:
                            ///< the batch's region placements and the resolve launches)
  double wait_seconds = 0;  ///< host waiting for the device to finish earlier batches
  double sync_seconds = 0;  ///< synchronise(): final wait plus downloads
  // ---- the CPU backend on several threads (0 otherwise): where its batches' time went ----
  double survey_seconds = 0;      ///< parallel: rays walked at region level, spans recorded
  double serial_seconds = 0;      ///< one thread: the batches' regions created, assigned to workers
  double resolve_seconds = 0;     ///< parallel: new regions cleared, spans dealt to their owners
  double apply_seconds = 0;       ///< parallel: voxel walks, until the last worker finished
  double apply_busy_seconds = 0;  ///< the workers' voxel-walk times summed (balance: this over
                                  ///< apply_seconds x threads)
};

/// @brief Integrates batches of prepared rays into the map it was created for.
/// With per-scan semantics each call must hold exactly one scan ("occupied wins" applies within a
/// call). Implementations document their thread-safety; none may be called concurrently.
class Backend {
 public:
  virtual ~Backend() = default;
  Backend() = default;
  Backend(const Backend&) = delete;
  Backend& operator=(const Backend&) = delete;

  /// @brief Short name: "cpu", "opencl", "cuda".
  virtual const char* name() const noexcept = 0;
  /// @brief The device in words ("AMD EPYC ... (PoCL 3.1)"); empty for the CPU backend.
  virtual std::string deviceName() const { return {}; }
  /// @brief A non-fatal problem met at start-up that the user should hear about (a device backend
  /// whose binary cache is not writable); empty when there was none.
  virtual std::string startupWarning() const { return {}; }
  /// @brief Host threads used for integration.
  virtual unsigned threads() const noexcept = 0;
  /// @brief Prepared rays per batch (RayBatcher's capacity) this backend works best with, for
  /// callers that leave the batch size to it (`--batch-rays` not given, MapperConfig::batch_rays
  /// 0). Devices want large launches; the CPU backend asks for less where the map does not
  /// depend on batch boundaries (cpu_backend.cpp).
  virtual std::size_t preferredBatchRays() const noexcept { return kLargeBatchRays; }
  /// The batch size of the devices and of maps whose result depends on batch boundaries.
  static constexpr std::size_t kLargeBatchRays = std::size_t{1} << 18;
  /// A job for runOnHostThreads(): called once for each part 0..parts-1.
  using HostJob = void (*)(void* context, unsigned part, unsigned parts);
  /// @brief Runs `job` on the backend's own host threads, one part each, the calling thread among
  /// them, and returns when every part is done; a backend without host threads runs one part on
  /// the calling thread. RayBatcher prepares a batch's rays so. Not concurrently with integrate().
  /// @rt allocates: no; throws: no (wakes the workers: a mutex and a condition variable).
  virtual void runOnHostThreads(HostJob job, void* context) noexcept { job(context, 0, 1); }
  /// @brief Integrates one batch. @rt allocates: no; throws: no.
  virtual Expected<void, IntegrateError> integrate(std::span<const PreparedRay> rays) noexcept = 0;
  /// @brief Whether integrateRays() prepares rays under `filter` on the device (device backends
  /// planning and preparing on the device, with double precision, for filters without
  /// segmentation). The default: no; RayBatcher then prepares on the host.
  virtual bool preparesOnDevice(const RayFilter& filter) const noexcept {
    (void)filter;
    return false;
  }
  /// @brief Whether integratePoints() deskews `points` points with tables of these sizes on the
  /// device (preparesOnDevice(), the tables within the device's limits, and per scan at most one
  /// device batch). The default: no.
  virtual bool deskewsOnDevice(const RayFilter& filter, const DeskewTables& tables,
                               std::size_t points) const noexcept {
    (void)filter;
    (void)tables;
    (void)points;
    return false;
  }
  /// @brief integrateRays() of the rays deskewedRay() makes of `points`, with the deskewing on
  /// the device too. Only where deskewsOnDevice(); the default fails.
  virtual Expected<std::size_t, IntegrateError> integratePoints(
      const RayPreparer& preparer, const rm_prepare_params& params,
      std::span<const rm_scan_point> points, const DeskewTables& tables,
      RayCounters& counters) noexcept {
    (void)preparer;
    (void)params;
    (void)points;
    (void)tables;
    (void)counters;
    return Unexpected(IntegrateError::kDeviceFailure);
  }
  /// @brief Integrates world-frame `rays` exactly as integrate() integrates what
  /// `preparer.prepareWith(params, ...)` makes of them (one call is one scan with per-scan
  /// semantics), with the preparation on the device; adds what happened to each ray to
  /// `counters` as prepareWith() counts it. Returns the prepared rays integrated. Only where
  /// preparesOnDevice(preparer.filter()); the default fails. @rt allocates: no; throws: no.
  virtual Expected<std::size_t, IntegrateError> integrateRays(const RayPreparer& preparer,
                                                              const rm_prepare_params& params,
                                                              std::span<const Ray> rays,
                                                              RayCounters& counters) noexcept {
    (void)preparer;
    (void)params;
    (void)rays;
    (void)counters;
    return Unexpected(IntegrateError::kDeviceFailure);
  }
  /// @brief Waits for the device and makes the host region store current (device backends
  /// download what changed; CPU: no-op). Call before reading the map (export, save, summarise);
  /// device counters of batches still in flight are only in stats() after it.
  virtual Expected<void, IntegrateError> synchronise() noexcept = 0;
  virtual BackendStats stats() const noexcept = 0;
};

}  // namespace raymap
