// SPDX-License-Identifier: BSD-3-Clause
// OpenCL backend: device buffers, batch submission and region transfers.
#include "src/opencl/opencl_backend.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <optional>
#include <vector>

#include "kernels/common/batch.h"
#include "src/gpu/batch_plan.hpp"
#include "src/gpu/device_region_cache.hpp"

namespace raymap {
namespace kernels {
extern const char* const kIntegrateOccupancySource;  // embedded at build time
}  // namespace kernels

namespace {

static_assert(sizeof(rm_span_record) == 32, "device ABI");
static_assert(sizeof(rm_hit_group) == 16, "device ABI");
static_assert(sizeof(rm_integrate_params) == 48, "device ABI");

using Clock = std::chrono::steady_clock;

double secondsSince(Clock::time_point start) noexcept {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

// Work-group size for the kernels (clamped to the device maximum).
constexpr std::size_t kWorkGroup = 64;

/// One set of batch staging buffers (host arrays and their device copies). Two sets alternate so
/// that the host plans batch N+1 while the device runs batch N.
struct StagingSet {
  gpu::BatchArrays arrays;
  opencl::BufferHandle rays;
  opencl::BufferHandle spans;
  opencl::BufferHandle groups;
  opencl::BufferHandle hit_rays;
  opencl::BufferHandle counters;
  opencl::BufferHandle scratch;  // per-ray semantics: saved values and runs of misses
  std::array<std::uint64_t, RM_COUNTER_COUNT> counters_host{};  // 64- or 32-bit words
  opencl::EventHandle done;  // completes when the set's counters have been read back
};

/// Rays and spans per device batch for the map's semantics (8 spans per ray on average is far
/// more than lidar rays need; a batch also ends when its spans run out).
gpu::BatchLimits batchLimits(const VoxelMap& map, const OpenClBackendOptions& options) {
  const std::size_t rays = map.semantics() == Semantics::kPerScan
                               ? options.batch_rays
                               : std::min(options.batch_rays, options.per_ray_batch_rays);
  return gpu::BatchLimits{rays, rays * 8};
}

class OpenClBackend final : public Backend, private gpu::RegionTransfer {
 public:
  /// slots == 0: shared memory (the device works on the host store in place).
  OpenClBackend(VoxelMap& map, opencl::DeviceContext ctx, std::uint32_t slots, bool int64_counters,
                const OpenClBackendOptions& options)
      : map_(map),
        ctx_(std::move(ctx)),
        cache_(slots > 0 ? std::optional<gpu::DeviceRegionCache>(std::in_place, slots)
                         : std::nullopt),
        limits_(batchLimits(map, options)),
        planner_(map, cache_ ? &*cache_ : nullptr, *this, limits_),
        int64_counters_(int64_counters) {
    params_.occupancy = map.occupancy().toKernel();
    params_.region_voxels = map.geometry().region_voxels;
    params_.voxels_per_region = map.store().voxelsPerRegion();
    params_.per_scan = map.semantics() == Semantics::kPerScan ? 1u : 0u;
    params_.has_mean = map.meanLayer() >= 0 ? 1u : 0u;
    stats_.cache_slots = slots > 0 ? slots : map.store().capacity();
    local_size_ = std::min(kWorkGroup, std::max<std::size_t>(ctx_.info.max_work_group_size, 1));
  }

  ~OpenClBackend() override {
    if (ctx_.queue) {
      (void)clFinish(ctx_.queue.get());
    }
  }

  /// Allocates device memory and builds kernels; called once by the factory.
  Expected<void, Error> initialise(const OpenClBackendOptions& options) {
    const std::string options_text =
        std::string("-cl-std=CL1.2") + (int64_counters_ ? " -DRM_HAVE_INT64_ATOMICS=1" : "") +
        (options.extra_build_options.empty() ? "" : " " + options.extra_build_options);
    auto program = opencl::buildProgram(ctx_, kernels::kIntegrateOccupancySource, options_text,
                                        options.program_cache);
    if (!program) {
      return Unexpected(program.error());
    }
    program_warning_ = program->warning;
    program_ = std::move(program->program);
    auto spans = opencl::createKernel(program_, "rm_integrate_spans");
    if (!spans) {
      return Unexpected(spans.error());
    }
    span_kernel_ = std::move(*spans);
    auto hits = opencl::createKernel(program_, "rm_apply_hit_groups");
    if (!hits) {
      return Unexpected(hits.error());
    }
    hit_kernel_ = std::move(*hits);
    auto tags = opencl::createKernel(program_, "rm_tag_hit_groups");
    if (!tags) {
      return Unexpected(tags.error());
    }
    tag_kernel_ = std::move(*tags);

    const RegionStore& store = map_.store();
    const LayerSchema& schema = store.schema();
    layers_.resize(static_cast<std::size_t>(schema.size()));
    for (int l = 0; l < schema.size(); ++l) {
      const std::string what = (cache_ ? "device region cache, layer '" : "shared map, layer '") +
                               std::string(schema.at(l).name) + "'";
      if (!cache_) {
        // Layer l of every slot is one array in the host store: the device uses it in place.
        auto buffer = opencl::createHostBuffer(ctx_, store.layerBytes(0, l),
                                               store.layerRegionBytes(l) * store.capacity(), what);
        if (!buffer) {
          return Unexpected(buffer.error());
        }
        layers_[static_cast<std::size_t>(l)] = std::move(*buffer);
        continue;
      }
      const std::size_t bytes = store.layerRegionBytes(l) * cache_->capacity();
      auto buffer = opencl::createBuffer(ctx_, bytes, what);
      if (!buffer) {
        return Unexpected(buffer.error());
      }
      layers_[static_cast<std::size_t>(l)] = std::move(*buffer);
      // Touch all of the cache now, at start-up: drivers (and PoCL, whose device memory is host
      // memory) commit pages on first use, and integration must not stall on that later.
      const LayerSpec& spec = schema.at(l);
      if (clEnqueueFillBuffer(ctx_.queue.get(), layers_[static_cast<std::size_t>(l)].get(),
                              spec.clear_words.data(), spec.bytes_per_voxel, 0, bytes, 0, nullptr,
                              nullptr) != CL_SUCCESS) {
        return fail(ErrorCode::kCapacity, "OpenCL " + what + ": cannot initialise " +
                                              std::to_string(bytes) + " bytes on " +
                                              ctx_.info.device_name);
      }
    }
    auto dummy = opencl::createBuffer(ctx_, 8, "placeholder for absent layers");
    if (!dummy) {
      return Unexpected(dummy.error());
    }
    dummy_ = std::move(*dummy);
    const std::size_t counter_bytes = RM_COUNTER_COUNT * (int64_counters_ ? 8u : 4u);
    for (StagingSet& set : sets_) {
      planner_.reserve(set.arrays);
      for (auto [handle, bytes, what] :
           {std::tuple{&set.rays, limits_.max_rays * sizeof(PreparedRay), "ray batch"},
            std::tuple{&set.spans, limits_.max_spans * sizeof(rm_span_record), "span batch"},
            std::tuple{&set.groups, limits_.max_rays * sizeof(rm_hit_group), "hit groups"},
            std::tuple{&set.hit_rays, limits_.max_rays * sizeof(std::uint32_t), "hit list"},
            std::tuple{&set.counters, counter_bytes, "counters"},
            std::tuple{&set.scratch,
                       std::size_t{RM_SCRATCH_WORDS(limits_.max_rays, limits_.max_rays)} * 4u,
                       "batch scratch"}}) {
        auto buffer = opencl::createBuffer(ctx_, bytes, what);
        if (!buffer) {
          return Unexpected(buffer.error());
        }
        *handle = std::move(*buffer);
      }
    }
    if (const cl_int status = clFinish(ctx_.queue.get()); status != CL_SUCCESS) {
      return fail(ErrorCode::kCapacity, std::string("OpenCL device region cache: ") +
                                            opencl::errorName(status) + " on " +
                                            ctx_.info.device_name);
    }
    return {};
  }

  const char* name() const noexcept override { return "opencl"; }
  std::string deviceName() const override {
    return ctx_.info.device_name + " (" + ctx_.info.platform_name + ")" +
           (cache_ ? "" : ", shared memory");
  }
  std::string startupWarning() const override { return program_warning_; }
  unsigned threads() const noexcept override { return 1; }

  Expected<void, IntegrateError> integrate(std::span<const PreparedRay> rays) noexcept override {
    params_.sequence = params_.per_scan != 0u ? map_.beginScan() : 0u;
    planner_.revalidate();
    while (!rays.empty()) {
      StagingSet& set = sets_[next_set_];
      const Clock::time_point t_wait = Clock::now();
      if (auto ok = retire(set); !ok) {
        return ok;
      }
      const Clock::time_point t_plan = Clock::now();
      stats_.wait_seconds += std::chrono::duration<double>(t_plan - t_wait).count();
      auto consumed = planner_.plan(rays, set.arrays);
      stats_.plan_seconds += secondsSince(t_plan);
      if (!consumed) {
        return Unexpected(consumed.error());
      }
      rays = rays.subspan(*consumed);
      if (set.arrays.rays.empty()) {
        continue;  // every ray was skipped
      }
      if (auto ok = submit(set); !ok) {
        return ok;
      }
      next_set_ ^= 1u;
    }
    ++stats_.batches;
    return {};
  }

  Expected<void, IntegrateError> synchronise() noexcept override {
    const Clock::time_point start = Clock::now();
    if (clFinish(ctx_.queue.get()) != CL_SUCCESS) {
      return Unexpected(IntegrateError::kDeviceFailure);
    }
    for (StagingSet& set : sets_) {
      if (auto ok = retire(set); !ok) {
        return ok;
      }
    }
    auto ok = planner_.downloadAll();
    if (ok && !cache_) {
      ok = syncSharedLayers();
    }
    if (ok && clFinish(ctx_.queue.get()) != CL_SUCCESS) {
      ok = Unexpected(IntegrateError::kDeviceFailure);
    }
    stats_.sync_seconds += secondsSince(start);
    return ok;
  }

  BackendStats stats() const noexcept override {
    BackendStats s = stats_;
    const gpu::PlanStats& p = planner_.stats();
    s.spans_outside_window = p.spans_outside_window;
    s.rays_skipped = p.rays_too_long;
    s.cache_hits = cache_ ? cache_->hits() : p.region_hits;
    s.cache_misses = cache_ ? cache_->misses() : p.region_misses;
    s.cache_evictions = cache_ ? cache_->evictions() : 0;
    return s;
  }

 private:
  // ---- gpu::RegionTransfer ----
  Expected<void, IntegrateError> download(std::uint32_t device_slot,
                                          std::uint32_t host_slot) noexcept override {
    return copyRegion(device_slot, host_slot, /*to_device=*/false);
  }
  Expected<void, IntegrateError> upload(std::uint32_t device_slot,
                                        std::uint32_t host_slot) noexcept override {
    return copyRegion(device_slot, host_slot, /*to_device=*/true);
  }
  Expected<void, IntegrateError> fillClear(std::uint32_t device_slot) noexcept override {
    const RegionStore& store = map_.store();
    for (int l = 0; l < store.schema().size(); ++l) {
      const LayerSpec& spec = store.schema().at(l);
      const std::size_t bytes = store.layerRegionBytes(l);
      if (clEnqueueFillBuffer(ctx_.queue.get(), layers_[static_cast<std::size_t>(l)].get(),
                              spec.clear_words.data(), spec.bytes_per_voxel, bytes * device_slot,
                              bytes, 0, nullptr, nullptr) != CL_SUCCESS) {
        return Unexpected(IntegrateError::kDeviceFailure);
      }
    }
    return {};
  }

  /// Copies every layer of one region. Uploads block, so the host store slot may be reused at
  /// once (they happen only on cache misses of regions that exist on the host). Downloads do not:
  /// the in-order queue runs them before anything enqueued later (an upload of the same host
  /// memory included), and the host reads the store only after synchronise(), which waits.
  Expected<void, IntegrateError> copyRegion(std::uint32_t device_slot, std::uint32_t host_slot,
                                            bool to_device) noexcept {
    const RegionStore& store = map_.store();
    for (int l = 0; l < store.schema().size(); ++l) {
      const std::size_t bytes = store.layerRegionBytes(l);
      cl_mem buffer = layers_[static_cast<std::size_t>(l)].get();
      std::byte* host = store.layerBytes(host_slot, l);
      const cl_int status =
          to_device ? clEnqueueWriteBuffer(ctx_.queue.get(), buffer, CL_TRUE, bytes * device_slot,
                                           bytes, host, 0, nullptr, nullptr)
                    : clEnqueueReadBuffer(ctx_.queue.get(), buffer, CL_FALSE, bytes * device_slot,
                                          bytes, host, 0, nullptr, nullptr);
      if (status != CL_SUCCESS) {
        return Unexpected(IntegrateError::kDeviceFailure);
      }
      (to_device ? stats_.bytes_to_device : stats_.bytes_from_device) += bytes;
      (to_device ? stats_.region_bytes_to_device : stats_.region_bytes_from_device) += bytes;
    }
    return {};
  }

  /// Shared memory: mapping a CL_MEM_USE_HOST_PTR buffer is what makes the device's writes
  /// visible in the host memory by the standard (on shared-memory devices it copies nothing).
  Expected<void, IntegrateError> syncSharedLayers() noexcept {
    const RegionStore& store = map_.store();
    for (int l = 0; l < store.schema().size(); ++l) {
      cl_mem buffer = layers_[static_cast<std::size_t>(l)].get();
      const std::size_t bytes = store.layerRegionBytes(l) * store.capacity();
      cl_int status = CL_SUCCESS;
      void* mapped =
          clEnqueueMapBuffer(ctx_.queue.get(), buffer, CL_TRUE, CL_MAP_READ | CL_MAP_WRITE, 0,
                             bytes, 0, nullptr, nullptr, &status);
      if (status != CL_SUCCESS || clEnqueueUnmapMemObject(ctx_.queue.get(), buffer, mapped, 0,
                                                          nullptr, nullptr) != CL_SUCCESS) {
        return Unexpected(IntegrateError::kDeviceFailure);
      }
    }
    return {};
  }

  /// Waits for the set's previous batch (if any) and adds its device counters to the stats.
  Expected<void, IntegrateError> retire(StagingSet& set) noexcept {
    if (!set.done) {
      return {};
    }
    const cl_event event = set.done.get();
    const cl_int status = clWaitForEvents(1, &event);
    set.done.reset();
    if (status != CL_SUCCESS) {
      return Unexpected(IntegrateError::kDeviceFailure);
    }
    std::uint64_t visits = 0;
    std::uint64_t dropped = 0;
    if (int64_counters_) {
      for (std::uint32_t b = 0; b < RM_COUNTER_BUCKETS; ++b) {
        visits += set.counters_host[b];
      }
      dropped = set.counters_host[RM_COUNTER_DROPPED];
    } else {
      const auto* words = reinterpret_cast<const std::uint32_t*>(set.counters_host.data());
      for (std::uint32_t b = 0; b < RM_COUNTER_BUCKETS; ++b) {
        visits += words[b];
      }
      dropped = words[RM_COUNTER_DROPPED];
    }
    stats_.voxels_visited += visits;
    stats_.updates_dropped += dropped;
    return {};
  }

  /// Enqueues the batch in `set`: copies, kernels in the semantics' order, counter read-back.
  Expected<void, IntegrateError> submit(StagingSet& set) noexcept {
    const gpu::BatchArrays& a = set.arrays;
    cl_command_queue q = ctx_.queue.get();
    bool ok = true;
    auto write = [&](const opencl::BufferHandle& buffer, const void* data, std::size_t bytes) {
      if (bytes > 0 && ok) {
        ok = clEnqueueWriteBuffer(q, buffer.get(), CL_FALSE, 0, bytes, data, 0, nullptr, nullptr) ==
             CL_SUCCESS;
        stats_.bytes_to_device += bytes;
      }
    };
    write(set.rays, a.rays.data(), a.rays.size() * sizeof(PreparedRay));
    write(set.spans, a.spans.data(), a.spans.size() * sizeof(rm_span_record));
    write(set.groups, a.groups.data(), a.groups.size() * sizeof(rm_hit_group));
    write(set.hit_rays, a.hit_rays.data(), a.hit_rays.size() * sizeof(std::uint32_t));
    const std::uint32_t zero = 0;
    const std::size_t counter_bytes = RM_COUNTER_COUNT * (int64_counters_ ? 8u : 4u);
    ok = ok && clEnqueueFillBuffer(q, set.counters.get(), &zero, sizeof(zero), 0, counter_bytes, 0,
                                   nullptr, nullptr) == CL_SUCCESS;
    if (params_.per_scan != 0u) {
      ok = ok && launchHits(set) && launchSpans(set);  // hits first: occupied wins
    } else {
      // Tag the voxels with samples, walk the misses, replay the tagged voxels in ray order.
      const std::size_t runs = a.hit_rays.size() + a.groups.size();
      ok = ok && (runs == 0 || clEnqueueFillBuffer(q, set.scratch.get(), &zero, sizeof(zero),
                                                   a.groups.size() * 4u, runs * 4u, 0, nullptr,
                                                   nullptr) == CL_SUCCESS);
      ok = ok && launchTags(set) && launchSpans(set) && launchHits(set);
    }
    cl_event done = nullptr;
    ok = ok && clEnqueueReadBuffer(q, set.counters.get(), CL_FALSE, 0, counter_bytes,
                                   set.counters_host.data(), 0, nullptr, &done) == CL_SUCCESS;
    if (!ok) {
      return Unexpected(IntegrateError::kDeviceFailure);
    }
    set.done = opencl::EventHandle(done);
    stats_.bytes_from_device += counter_bytes;
    (void)clFlush(q);  // start the device now; the host goes on planning
    stats_.rays += a.rays.size();
    return {};
  }

  cl_mem layerOr(int layer) const noexcept {
    return layer >= 0 ? layers_[static_cast<std::size_t>(layer)].get() : dummy_.get();
  }

  bool launch(cl_kernel kernel, std::uint32_t items) noexcept {
    if (items == 0) {
      return true;
    }
    const std::size_t local = local_size_;
    const std::size_t global = (items + local - 1) / local * local;
    return clEnqueueNDRangeKernel(ctx_.queue.get(), kernel, 1, nullptr, &global, &local, 0, nullptr,
                                  nullptr) == CL_SUCCESS;
  }

  /// Launch parameters of one kernel over `items` work-items.
  rm_integrate_params launchParams(const StagingSet& set, std::size_t items) const noexcept {
    rm_integrate_params p = params_;
    p.item_count = static_cast<std::uint32_t>(items);
    p.group_count = static_cast<std::uint32_t>(set.arrays.groups.size());
    return p;
  }

  /// Sets the kernel's arguments in order (buffers as cl_mem, the parameters by value).
  template <class... Args>
  static bool setArgs(cl_kernel k, const Args&... args) noexcept {
    cl_uint index = 0;
    return ((clSetKernelArg(k, index++, sizeof(Args), &args) == CL_SUCCESS) && ...);
  }

  bool launchTags(StagingSet& set) noexcept {
    const rm_integrate_params p = launchParams(set, set.arrays.groups.size());
    return setArgs(tag_kernel_.get(), set.groups.get(), layerOr(map_.occupancyLayer()),
                   set.scratch.get(), p) &&
           launch(tag_kernel_.get(), p.item_count);
  }

  bool launchSpans(StagingSet& set) noexcept {
    const rm_integrate_params p = launchParams(set, set.arrays.spans.size());
    return setArgs(span_kernel_.get(), set.rays.get(), set.spans.get(), set.groups.get(),
                   set.hit_rays.get(), layerOr(map_.occupancyLayer()),
                   layerOr(map_.scanMarkLayer()), set.scratch.get(), p, set.counters.get()) &&
           launch(span_kernel_.get(), p.item_count);
  }

  bool launchHits(StagingSet& set) noexcept {
    const rm_integrate_params p = launchParams(set, set.arrays.groups.size());
    return setArgs(hit_kernel_.get(), set.rays.get(), set.groups.get(), set.hit_rays.get(),
                   layerOr(map_.occupancyLayer()), layerOr(map_.meanLayer()),
                   layerOr(map_.scanMarkLayer()), set.scratch.get(), p, set.counters.get()) &&
           launch(hit_kernel_.get(), p.item_count);
  }

  VoxelMap& map_;
  opencl::DeviceContext ctx_;  // first member with handles: released last
  opencl::ProgramHandle program_;
  opencl::KernelHandle span_kernel_;
  opencl::KernelHandle hit_kernel_;
  opencl::KernelHandle tag_kernel_;
  std::vector<opencl::BufferHandle> layers_;  // one per schema layer: the cache slots
  opencl::BufferHandle dummy_;
  std::optional<gpu::DeviceRegionCache> cache_;  // empty: shared memory
  gpu::BatchLimits limits_;
  gpu::BatchPlanner planner_;
  std::array<StagingSet, 2> sets_;
  unsigned next_set_ = 0;
  bool int64_counters_;
  std::size_t local_size_ = kWorkGroup;
  rm_integrate_params params_{};
  BackendStats stats_;
  std::string program_warning_;
};

/// Device cache slots for the options: the byte budget over the bytes of one region (all layers),
/// capped by the host store, the largest single allocation and 32-bit voxel indices.
Result<std::uint32_t> cacheSlots(const VoxelMap& map, const opencl::DeviceInfo& device,
                                 std::uint64_t cache_bytes, std::uint32_t cache_regions) {
  const RegionStore& store = map.store();
  std::uint64_t region_bytes = 0;
  std::uint64_t largest_layer = 0;
  for (int l = 0; l < store.schema().size(); ++l) {
    region_bytes += store.layerRegionBytes(l);
    largest_layer = std::max<std::uint64_t>(largest_layer, store.layerRegionBytes(l));
  }
  std::uint64_t budget = cache_bytes;
  if (budget == 0) {
    budget = std::min<std::uint64_t>(OpenClBackendOptions::kDefaultCacheBytes,
                                     device.global_mem_bytes / 2);
  }
  std::uint64_t slots = cache_regions > 0 ? cache_regions : budget / region_bytes;
  slots = std::min<std::uint64_t>(slots, store.capacity());
  slots = std::min<std::uint64_t>(slots, device.max_alloc_bytes / largest_layer);
  slots = std::min<std::uint64_t>(slots, (std::uint64_t{1} << 32) / store.voxelsPerRegion() - 1);
  if (slots == 0) {
    return fail(ErrorCode::kInvalidArgument,
                "the OpenCL region cache of " + std::to_string(budget) +
                    " bytes cannot hold one region of " + std::to_string(region_bytes) +
                    " bytes; raise --gpu-cache");
  }
  return static_cast<std::uint32_t>(slots);
}

/// Whether the device should work on the host store in place: asked for, or (auto) the device
/// shares memory with the host and every layer of the store fits one allocation.
bool useSharedMemory(const VoxelMap& map, const opencl::DeviceInfo& device, DeviceMemory memory) {
  if (memory != DeviceMemory::kAuto) {
    return memory == DeviceMemory::kShared;
  }
  const RegionStore& store = map.store();
  if (!device.unified_memory ||
      std::uint64_t{store.capacity()} * store.voxelsPerRegion() >= (std::uint64_t{1} << 32)) {
    return false;
  }
  for (int l = 0; l < store.schema().size(); ++l) {
    if (std::uint64_t{store.layerRegionBytes(l)} * store.capacity() > device.max_alloc_bytes) {
      return false;
    }
  }
  return true;
}

}  // namespace

Result<std::unique_ptr<Backend>> createOpenClBackend(VoxelMap& map,
                                                     const OpenClBackendOptions& options) {
  if (map.occupancyLayer() < 0) {
    return fail(ErrorCode::kInvalidArgument, "the OpenCL backend needs an occupancy layer");
  }
  if (options.batch_rays == 0 || options.batch_rays > (std::size_t{1} << 24) ||
      options.per_ray_batch_rays == 0 || options.per_ray_batch_rays > RM_TAG_MAX_GROUPS) {
    return fail(ErrorCode::kInvalidArgument,
                "OpenCL batch sizes must be 1 to 16777216 rays (per-ray: 1 to 4194304)");
  }
  auto devices = opencl::listDevices();
  if (!devices) {
    return Unexpected(devices.error());
  }
  auto device = opencl::selectDevice(*devices, options.device);
  if (!device) {
    return Unexpected(device.error());
  }
  std::uint32_t slots = 0;  // 0: shared memory
  if (!useSharedMemory(map, *device, options.memory)) {
    auto cache_slots = cacheSlots(map, *device, options.cache_bytes, options.cache_regions);
    if (!cache_slots) {
      return Unexpected(cache_slots.error());
    }
    slots = *cache_slots;
  } else if (options.memory == DeviceMemory::kShared && !device->unified_memory) {
    return fail(ErrorCode::kUnsupported,
                "shared device memory: " + device->device_name +
                    " does not share memory with the host; use the region cache");
  }
  auto ctx = opencl::createContext(*device);
  if (!ctx) {
    return Unexpected(ctx.error());
  }
  const bool int64_counters = device->int64_atomics && !options.force_32bit_atomics;
  auto backend =
      std::make_unique<OpenClBackend>(map, std::move(*ctx), slots, int64_counters, options);
  if (auto ok = backend->initialise(options); !ok) {
    return Unexpected(ok.error());
  }
  return std::unique_ptr<Backend>(std::move(backend));
}

}  // namespace raymap
