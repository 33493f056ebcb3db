// SPDX-License-Identifier: BSD-3-Clause
// CPU backend: the single-threaded reference or the region-partitioned multi-threaded path.
#include "src/map/cpu_backend.hpp"

#include <optional>
#include <string>
#include <vector>

#include "platform/process.hpp"
#include "src/map/cpu_parallel.hpp"
#include "src/map/cpu_serial.hpp"
#include "src/map/scan_bits.hpp"

namespace raymap {

const char* toString(IntegrateError error) noexcept {
  switch (error) {
    case IntegrateError::kStoreFull:
      return "region store full";
    case IntegrateError::kDeviceFailure:
      return "device failure";
    case IntegrateError::kTierFailed:
      return "the map's cold tiers failed";
    case IntegrateError::kOutOfMemory:
      return "the host refused memory for the batch's scratch lists";
  }
  return "unknown integration error";
}

namespace {

class CpuBackend final : public Backend {
 public:
  CpuBackend(VoxelMap& map, unsigned threads, std::size_t expected_batch_rays) : map_(map) {
    ctx_.map = &map;
    ctx_.region_voxels = map.geometry().region_voxels;
    ctx_.params = map.occupancy().toKernel();
    ctx_.per_scan = map.semantics() == Semantics::kPerScan;
    ctx_.ndt = isNdt(map.mode());
    ctx_.resolution = static_cast<float>(map.geometry().resolution);
    ctx_.tsdf_params = map.config().tsdf.toKernel(map.geometry().resolution);
    ctx_.ndt_params =
        map.config().ndt.toKernel(map.geometry().resolution, map.occupancy(), map.mode());
    if (threads > 1) {
      parallel_.emplace(threads, map.store().capacity(), ctx_.region_voxels,
                        expected_batch_rays != 0 ? expected_batch_rays : preferredBatchRays());
    }
    if (ctx_.per_scan) {
      scan_bits_.emplace(map.store().capacity(), ctx_.region_voxels);
      ctx_.scan_bits = &*scan_bits_;
    }
    caches_.assign(this->threads(), detail::RegionSlotCache{});
    worker_stats_.assign(this->threads(), detail::WorkerStats{});
  }

  const char* name() const noexcept override { return "cpu"; }
  unsigned threads() const noexcept override { return parallel_ ? parallel_->workers() : 1u; }
  /// Per-ray maps other than NDT give the same map whatever the batch boundaries (updates in ray
  /// order), and smaller batches keep a batch's prepared rays and the parallel integrator's span
  /// records in cache and resident: on the Ouster data, a fresh map per ray ran at 1.03 M rays/s
  /// on 2 threads with 32,768-ray batches and 0.51 M with 262,144 (peak RSS 160 MB against
  /// 307 MB), and 0.70 M against 0.62 M on one thread. A per-scan batch holds a whole scan, and
  /// an NDT batch's misses come before its hits: those keep the large batch.
  std::size_t preferredBatchRays() const noexcept override {
    return ctx_.per_scan || ctx_.ndt ? kLargeBatchRays : kCpuBatchRays;
  }
  static constexpr std::size_t kCpuBatchRays = std::size_t{1} << 15;
  void runOnHostThreads(HostJob job, void* context) noexcept override {
    if (!parallel_) {
      job(context, 0, 1);
      return;
    }
    const unsigned parts = parallel_->workers();
    auto run = [&](unsigned part) { job(context, part, parts); };
    parallel_->pool().run(run);
  }

  Expected<void, IntegrateError> integrate(std::span<const PreparedRay> rays) noexcept override {
    Expected<void, IntegrateError> result = integrateWhole(rays);
    if (result || result.error() != IntegrateError::kStoreFull || !map_.tiered() ||
        !detail::splitsAtAnyRay(ctx_) || !parallel_) {
      return result;  // (the serial path unpins the pool as it goes: see cpu_serial.cpp)
    }
    // A tiered map whose pool cannot hold the batch's regions at once: the parallel path fails
    // before it changes anything, so the batch goes in by halves, down to single rays, which the
    // serial path takes region by region. Any budget that holds one region works.
    ++stats_.batches_split;
    if (rays.size() == 1) {
      return integrateWhole(rays, /*serially=*/true);
    }
    const std::size_t half = rays.size() / 2;
    if (auto first = integrate(rays.first(half)); !first) {
      return first;
    }
    return integrate(rays.subspan(half));
  }

  Expected<void, IntegrateError> synchronise() noexcept override { return {}; }
  BackendStats stats() const noexcept override {
    BackendStats s = stats_;
    if (parallel_) {
      const detail::ParallelIntegrator::StepSeconds& steps = parallel_->stepSeconds();
      s.survey_seconds = steps.survey;
      s.serial_seconds = steps.serial;
      s.resolve_seconds = steps.resolve;
      s.apply_seconds = steps.apply;
      s.apply_busy_seconds = steps.apply_busy;
    }
    return s;
  }

 private:
  /// One batch as it is (the parallel path when there are threads, unless `serially`).
  Expected<void, IntegrateError> integrateWhole(std::span<const PreparedRay> rays,
                                                bool serially = false) noexcept {
    const VoxelMap::IntegrationScope integrating(map_);
    ctx_.sequence = ctx_.per_scan ? map_.beginScan() : 0u;
    if (scan_bits_) {
      scan_bits_->beginBatch(ctx_.sequence);
    }
    map_.beginEpoch();  // a tiered map keeps this batch's regions in the pool
    for (detail::RegionSlotCache& cache : caches_) {
      cache.reset();  // regions may have been recycled since the last batch
    }
    Expected<void, IntegrateError> result =
        parallel_ && !serially ? parallel_->integrate(ctx_, rays, caches_, worker_stats_)
                               : detail::integrateSerial(ctx_, rays, caches_[0], worker_stats_[0]);
    for (detail::WorkerStats& w : worker_stats_) {
      stats_.voxels_visited += w.voxels_visited;
      stats_.spans_outside_window += w.spans_outside_window;
      w = detail::WorkerStats{};
    }
    if (result) {
      ++stats_.batches;
      stats_.rays += rays.size();
    }
    return result;
  }

  VoxelMap& map_;
  detail::IntegrationContext ctx_;
  std::optional<detail::ParallelIntegrator> parallel_;
  std::optional<detail::ScanBits> scan_bits_;      // per-scan semantics
  std::vector<detail::RegionSlotCache> caches_;    // one per worker
  std::vector<detail::WorkerStats> worker_stats_;  // one per worker
  BackendStats stats_;
};

}  // namespace

Result<std::unique_ptr<Backend>> createCpuBackend(VoxelMap& map, const CpuBackendOptions& options) {
  const unsigned threads = options.threads == 0 ? platform::availableCores() : options.threads;
  if (threads > CpuBackendOptions::kMaxThreads) {
    return fail(ErrorCode::kInvalidArgument, "threads must be at most " +
                                                 std::to_string(CpuBackendOptions::kMaxThreads) +
                                                 " (got " + std::to_string(threads) + ")");
  }
  if (map.occupancyLayer() < 0 && map.tsdfLayer() < 0 && map.traversalLayer() < 0) {
    return fail(ErrorCode::kInvalidArgument,
                "the CPU backend needs an occupancy, traversal or TSDF layer to integrate into");
  }
  return std::unique_ptr<Backend>(new CpuBackend(map, threads, options.expected_batch_rays));
}

}  // namespace raymap
