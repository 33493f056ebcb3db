// SPDX-License-Identifier: BSD-3-Clause
// OpenCL backend: device buffers, the in-order command queue, kernel arguments. The batch loop,
// the kernel order and region moves are gpu::StagedBackend's.
#include "src/device/opencl/opencl_backend.hpp"

#include <algorithm>
#include <array>
#include <optional>
#include <string_view>
#include <tuple>
#include <vector>

#include "kernels/common/batch.h"
#include "src/device/staging/staged_backend.hpp"

namespace raymap {
namespace kernels {
extern const char* const kIntegrateOccupancySource;  // embedded at build time
extern const char* const kIntegrateNdtSource;        // embedded at build time
extern const char* const kPlanSource;                // embedded at build time
extern const char* const kPrepareSource;             // embedded at build time
}  // namespace kernels

namespace {

using gpu::NdtKernel;
using gpu::OccupancyKernel;
using gpu::PlanBuffer;

// Work-group size for the kernels (clamped to the device maximum).
constexpr std::size_t kWorkGroup = 64;
// Span work per region: work-items per compute unit. More than one, so a unit whose thread the
// OS takes away for a while does not hold runs the others could take.
constexpr std::size_t kRegionWorkersPerUnit = 2;

/// Device buffers of one staging set.
struct DeviceBatch {
  opencl::BufferHandle rays;
  opencl::BufferHandle spans;
  opencl::BufferHandle span_runs;  // span work per region: each region's run of spans
  opencl::BufferHandle next_run;   // span work per region: the next run to take (zeroed a batch)
  opencl::BufferHandle groups;
  opencl::BufferHandle hit_rays;
  opencl::BufferHandle counters;
  opencl::BufferHandle scratch;  // per-ray semantics: saved values and runs of misses
  std::array<std::uint64_t, RM_COUNTER_COUNT> counters_host{};  // 64- or 32-bit words
  opencl::EventHandle done;  // completes when the counters have been read back
  // Planning on the device: the planner's own buffers (PlanBuffer ids), and with span work per
  // region the span records as emitted (the kernels read the grouped ones in `spans`).
  std::array<opencl::BufferHandle, gpu::kPlanBufferCount> plan;
  opencl::BufferHandle emitted_spans;
  opencl::EventHandle plan_read;  // completes when the plan's read-back is in
};

class OpenClBackend final : public gpu::StagedBackend, public opencl::BackendDevice {
 public:
  /// slots == 0: shared memory (the device works on the host store in place).
  OpenClBackend(VoxelMap& map, opencl::DeviceContext ctx, std::uint32_t slots, bool int64_counters,
                const OpenClBackendOptions& options)
      : StagedBackend(map, slots, int64_counters, options),
        ctx_(std::move(ctx)),
        int64_counters_(int64_counters) {
    local_size_ = std::min(kWorkGroup, std::max<std::size_t>(ctx_.info.max_work_group_size, 1));
  }

  ~OpenClBackend() override {
    if (ctx_.queue) {
      (void)clFinish(ctx_.queue.get());
    }
  }

  /// Allocates device memory and builds kernels; called once by the factory.
  Expected<void, Error> initialise(const OpenClBackendOptions& options) {
    if (auto ok = checkMapIsSupported(); !ok) {
      return ok;
    }
    const bool by_region = options.span_work == SpanWork::kPerRegion ||
                           (options.span_work == SpanWork::kAuto && ctx_.info.type == "CPU");
    if (by_region) {
      try {
        groupSpansByRegion();
      } catch (const std::bad_alloc&) {
        return fail(ErrorCode::kCapacity,
                    "OpenCL backend: no host memory to group span records "
                    "by region (queues.batch_rays smaller)");
      }
    }
    if (auto ok = buildIntegrationProgram(options, by_region); !ok) {
      return ok;
    }
    if (auto ok = allocateLayers(); !ok) {
      return ok;
    }
    auto dummy = opencl::createBuffer(ctx_, 8, "placeholder for absent layers");
    if (!dummy) {
      return Unexpected(dummy.error());
    }
    dummy_ = std::move(*dummy);
    if (auto ok = allocateBatches(by_region); !ok) {
      return ok;
    }
    if (const cl_int status = clFinish(ctx_.queue.get()); status != CL_SUCCESS) {
      return fail(ErrorCode::kCapacity, std::string("OpenCL device region cache: ") +
                                            opencl::errorName(status) + " on " +
                                            ctx_.info.device_name);
    }
    if (options.planning == gpu::Planning::kDevice) {
      return initialisePlanning(options);
    }
    return {};
  }

  const char* name() const noexcept override { return "opencl"; }
  std::string deviceName() const override {
    return ctx_.info.device_name + " (" + ctx_.info.platform_name + ")" +
           (sharedMemory() ? ", shared memory" : "") +
           (spansByRegion() ? ", span work per region" : "") +
           (planning() == gpu::Planning::kDevice ? ", planned on the device" : "") +
           (preparesOnDevice(RayFilter{}) ? ", rays prepared on the device" : "");
  }
  std::string startupWarning() const override { return program_warning_; }

  // ---- opencl::BackendDevice ----
  const opencl::DeviceContext& context() const noexcept override { return ctx_; }
  cl_mem layerBuffer(int layer) const noexcept override { return layerOr(layer); }
  gpu::StagedBackend& staged() noexcept override { return *this; }

 private:
  /// The integration program for the map's mode and span work, and its kernels.
  Expected<void, Error> buildIntegrationProgram(const OpenClBackendOptions& options,
                                                bool by_region) {
    // The program is built for the map's mode (kernels/common/map_mode.h): kernels without the
    // branches of other modes. Each mode's binary has its own entry in the program cache.
    const std::string options_text =
        std::string("-cl-std=CL1.2 -DRM_MAP_MODE=") + std::to_string(mapMode()) + "u" +
        (int64_counters_ ? " -DRM_HAVE_INT64_ATOMICS=1" : "") +
        (by_region ? " -DRM_REGION_OWNED=1" : "") +
        (options.extra_build_options.empty() ? "" : " " + options.extra_build_options);
    // A map is integrated by one program: the occupancy kernels, or the NDT ones for NDT maps.
    const bool ndt = isNdt(map().mode());
    auto program = opencl::buildProgram(
        ctx_, ndt ? kernels::kIntegrateNdtSource : kernels::kIntegrateOccupancySource, options_text,
        options.program_cache);
    if (!program) {
      return Unexpected(program.error());
    }
    program_warning_ = program->warning;
    program_ = std::move(program->program);
    const char* span_name =
        ndt ? (by_region ? "rm_ndt_integrate_region_spans" : "rm_ndt_integrate_spans")
            : (by_region ? "rm_integrate_region_spans" : "rm_integrate_spans");
    auto kernels_made =
        ndt ? opencl::createKernels(
                  program_, {{&span_kernel_, span_name}, {&hit_kernel_, "rm_ndt_apply_hit_groups"}})
            : opencl::createKernels(program_, {{&span_kernel_, span_name},
                                               {&hit_kernel_, "rm_apply_hit_groups"},
                                               {&tag_kernel_, "rm_tag_hit_groups"}});
    return kernels_made;
  }

  /// Each batch set's device buffers, sized by the batch limits.
  Expected<void, Error> allocateBatches(bool by_region) {
    const gpu::BatchLimits& limits = this->limits();
    for (DeviceBatch& set : batches_) {
      for (auto [handle, bytes, what] :
           {std::tuple{&set.rays, limits.max_rays * sizeof(PreparedRay), "ray batch"},
            std::tuple{&set.spans, limits.max_spans * sizeof(rm_span_record), "span batch"},
            std::tuple{&set.span_runs,
                       by_region ? std::min<std::size_t>(limits.max_spans, layerRegions()) *
                                       sizeof(rm_span_run)
                                 : sizeof(rm_span_run),
                       "span runs"},
            std::tuple{&set.next_run, sizeof(std::uint32_t), "span run cursor"},
            std::tuple{&set.groups, limits.max_rays * sizeof(rm_hit_group), "hit groups"},
            std::tuple{&set.hit_rays, limits.max_rays * sizeof(std::uint32_t), "hit list"},
            std::tuple{&set.counters, counterBytes(), "counters"},
            std::tuple{&set.scratch, scratchWords() * 4u, "batch scratch"}}) {
        auto buffer = opencl::createBuffer(ctx_, bytes, what);
        if (!buffer) {
          return Unexpected(buffer.error());
        }
        *handle = std::move(*buffer);
      }
    }
    return {};
  }

  /// One buffer per map layer: the cache slots, or (shared memory) the host store's array.
  Expected<void, Error> allocateLayers() {
    const RegionStore& store = map().store();
    const LayerSchema& schema = store.schema();
    layers_.resize(static_cast<std::size_t>(schema.size()));
    for (int l = 0; l < schema.size(); ++l) {
      const std::string what =
          (sharedMemory() ? "shared map, layer '" : "device region cache, layer '") +
          std::string(schema.at(l).name) + "'";
      const std::size_t bytes = store.layerRegionBytes(l) * layerRegions();
      auto buffer = sharedMemory()
                        ? opencl::createHostBuffer(ctx_, store.layerBytes(0, l), bytes, what)
                        : opencl::createBuffer(ctx_, bytes, what);
      if (!buffer) {
        return Unexpected(buffer.error());
      }
      layers_[static_cast<std::size_t>(l)] = std::move(*buffer);
      // Touch all of the cache now, at start-up: drivers (and PoCL, whose device memory is host
      // memory) commit pages on first use, and integration must not stall on that later.
      if (!sharedMemory() && !fillLayer(l, 0, bytes, schema.at(l))) {
        return fail(ErrorCode::kCapacity, "OpenCL " + what + ": cannot initialise " +
                                              std::to_string(bytes) + " bytes on " +
                                              ctx_.info.device_name);
      }
    }
    return {};
  }

  /// Builds a planning program (`source`: plan.cl, or prepare.cl for the ray preparation) for
  /// work-groups of `group` into `program` and creates its kernels, planning kernels [first,
  /// last).
  Expected<void, Error> buildPlanningProgram(const OpenClBackendOptions& options,
                                             const char* source, std::size_t group,
                                             opencl::ProgramHandle& program, std::size_t first,
                                             std::size_t last) {
    auto built = opencl::buildProgram(
        ctx_, source,
        "-cl-std=CL1.2 -DRM_PLAN_GROUP=" + std::to_string(group) + "u" +
            (options.extra_build_options.empty() ? "" : " " + options.extra_build_options),
        options.program_cache);
    if (!built) {
      return Unexpected(built.error());
    }
    if (!built->warning.empty() && program_warning_.empty()) {
      program_warning_ = built->warning;
    }
    program = std::move(built->program);
    for (std::size_t k = first; k < last; ++k) {
      auto kernel =
          opencl::createKernel(program, gpu::planKernelName(static_cast<gpu::PlanKernel>(k)));
      if (!kernel) {
        return Unexpected(kernel.error());
      }
      plan_kernels_[k] = std::move(*kernel);
    }
    return {};
  }

  /// The planning program (kernels/opencl/plan.cl), its kernels and each set's buffers.
  Expected<void, Error> initialisePlanning(const OpenClBackendOptions& options) {
    // The planning kernels run in work-groups of a power of two from 64 to 256 work-items.
    std::size_t group = 256;
    while (group > ctx_.info.max_work_group_size && group > 64) {
      group /= 2;
    }
    if (group > ctx_.info.max_work_group_size) {
      return fail(ErrorCode::kUnsupported,
                  "planning on the device needs work-groups of 64 work-items; " +
                      ctx_.info.device_name + " allows " +
                      std::to_string(ctx_.info.max_work_group_size) +
                      " (use backend.device_planning: host)");
    }
    auto sizes = devicePlanSizesFor(static_cast<std::uint32_t>(group));
    if (!sizes) {
      return Unexpected(sizes.error());
    }
    // Rays are prepared in double precision, as on the host: without cl_khr_fp64 (Intel's Gen12
    // graphics) the host prepares them.
    sizes->prepare = options.prepare_on_device && ctx_.info.fp64;
    if (auto built = buildPlanningProgram(options, kernels::kPlanSource, group, plan_program_, 0,
                                          gpu::kFirstPrepareKernel);
        !built) {
      return built;
    }
    if (sizes->prepare) {
      if (auto built =
              buildPlanningProgram(options, kernels::kPrepareSource, group, prepare_program_,
                                   gpu::kFirstPrepareKernel, gpu::kPlanKernelCount);
          !built) {
        return built;
      }
    }
    plan_group_ = group;
    const gpu::BatchLimits& limits = this->limits();
    for (DeviceBatch& set : batches_) {
      for (std::size_t id = 0; id < gpu::kPlanBufferCount; ++id) {
        const std::size_t bytes = sizes->bytes(static_cast<PlanBuffer>(id));
        if (bytes == 0) {
          continue;
        }
        auto buffer = opencl::createBuffer(ctx_, bytes, "device planning");
        if (!buffer) {
          return Unexpected(buffer.error());
        }
        set.plan[id] = std::move(*buffer);
      }
      if (spansByRegion()) {
        auto buffer = opencl::createBuffer(ctx_, limits.max_spans * sizeof(rm_span_record),
                                           "device planning, span records");
        if (!buffer) {
          return Unexpected(buffer.error());
        }
        set.emitted_spans = std::move(*buffer);
      }
    }
    return planOnDevice(*sizes);
  }

  /// The buffer a planning kernel's argument `id` names on set `set`.
  cl_mem planBuffer(unsigned set, PlanBuffer id) const noexcept {
    const DeviceBatch& b = batches_[set];
    switch (id) {
      case PlanBuffer::kNone:
        return dummy_.get();
      case PlanBuffer::kRays:
        return b.rays.get();
      case PlanBuffer::kSpans:  // as emitted; grouped by region into `spans` for the kernels
        return spansByRegion() ? b.emitted_spans.get() : b.spans.get();
      case PlanBuffer::kRegionSpans:
        return spansByRegion() ? b.spans.get() : dummy_.get();
      case PlanBuffer::kSpanRuns:
        return b.span_runs.get();
      case PlanBuffer::kGroups:
        return b.groups.get();
      case PlanBuffer::kHitRays:
        return b.hit_rays.get();
      default:
        return b.plan[static_cast<std::size_t>(id)].get();
    }
  }

  // ---- gpu::PlanDevice ----
  bool launchPlan(unsigned set, const gpu::PlanLaunch& launch) noexcept override {
    cl_kernel k = plan_kernels_[static_cast<std::size_t>(launch.kernel)].get();
    if (clSetKernelArg(k, 0, sizeof(rm_plan_args), &launch.args) != CL_SUCCESS) {
      return false;
    }
    for (cl_uint i = 0; i < RM_PLAN_BUFFERS; ++i) {
      const cl_mem buffer = planBuffer(set, launch.buffers[i]);
      if (clSetKernelArg(k, i + 1, sizeof(cl_mem), &buffer) != CL_SUCCESS) {
        return false;
      }
    }
    const std::size_t local = plan_group_;
    const std::size_t global = (launch.items + local - 1) / local * local;
    return clEnqueueNDRangeKernel(ctx_.queue.get(), k, 1, nullptr, &global, &local, 0, nullptr,
                                  nullptr) == CL_SUCCESS;
  }

  bool writePlanBuffer(unsigned set, PlanBuffer buffer, std::size_t offset, const void* host,
                       std::size_t bytes) noexcept override {
    return bytes == 0 ||
           clEnqueueWriteBuffer(ctx_.queue.get(), planBuffer(set, buffer), CL_FALSE, offset, bytes,
                                host, 0, nullptr, nullptr) == CL_SUCCESS;
  }

  bool readPlanBuffer(unsigned set, PlanBuffer buffer, std::size_t offset, void* host,
                      std::size_t bytes) noexcept override {
    return bytes == 0 ||
           clEnqueueReadBuffer(ctx_.queue.get(), planBuffer(set, buffer), CL_FALSE, offset, bytes,
                               host, 0, nullptr, nullptr) == CL_SUCCESS;
  }

  bool markPlanRead(unsigned set) noexcept override {
    cl_event event = nullptr;
    if (clEnqueueMarkerWithWaitList(ctx_.queue.get(), 0, nullptr, &event) != CL_SUCCESS) {
      return false;
    }
    batches_[set].plan_read = opencl::EventHandle(event);
    return clFlush(ctx_.queue.get()) == CL_SUCCESS;
  }

  bool waitPlanRead(unsigned set) noexcept override {
    const cl_event event = batches_[set].plan_read.get();
    const cl_int status = event != nullptr ? clWaitForEvents(1, &event) : CL_INVALID_EVENT;
    batches_[set].plan_read.reset();
    return status == CL_SUCCESS;
  }

  // ---- gpu::StagedBackend ----
  bool uploadBatch(unsigned set, const gpu::BatchArrays* arrays) noexcept override {
    DeviceBatch& b = batches_[set];
    cl_command_queue q = ctx_.queue.get();
    bool ok = true;
    auto write = [&](const opencl::BufferHandle& buffer, const void* data, std::size_t bytes) {
      if (bytes > 0 && ok) {
        ok = clEnqueueWriteBuffer(q, buffer.get(), CL_FALSE, 0, bytes, data, 0, nullptr, nullptr) ==
             CL_SUCCESS;
      }
    };
    if (arrays != nullptr) {
      const gpu::BatchArrays& a = *arrays;
      write(b.rays, a.rays.data(), a.rays.size() * sizeof(PreparedRay));
      write(b.spans, a.deviceSpans().data(), a.deviceSpans().size() * sizeof(rm_span_record));
      write(b.span_runs, a.span_runs.data(), a.span_runs.size() * sizeof(rm_span_run));
      write(b.groups, a.groups.data(), a.groups.size() * sizeof(rm_hit_group));
      write(b.hit_rays, a.hit_rays.data(), a.hit_rays.size() * sizeof(std::uint32_t));
    }
    const std::uint32_t zero = 0;
    if (ok && spansByRegion()) {
      ok = clEnqueueFillBuffer(q, b.next_run.get(), &zero, sizeof(zero), 0, sizeof(zero), 0,
                               nullptr, nullptr) == CL_SUCCESS;
    }
    return ok && clEnqueueFillBuffer(q, b.counters.get(), &zero, sizeof(zero), 0, counterBytes(), 0,
                                     nullptr, nullptr) == CL_SUCCESS;
  }

  bool clearScratch(unsigned set, std::size_t first_word, std::size_t words) noexcept override {
    const std::uint32_t zero = 0;
    return clEnqueueFillBuffer(ctx_.queue.get(), batches_[set].scratch.get(), &zero, sizeof(zero),
                               first_word * 4u, words * 4u, 0, nullptr, nullptr) == CL_SUCCESS;
  }

  bool launch(OccupancyKernel kernel, unsigned set,
              const rm_integrate_params& p) noexcept override {
    const DeviceBatch& b = batches_[set];
    cl_kernel k = nullptr;
    bool ok = false;
    switch (kernel) {
      case OccupancyKernel::kTagHitGroups:
        k = tag_kernel_.get();
        ok = setArgs(k, b.groups.get(), layerOr(map().occupancyLayer()), b.scratch.get(), p);
        break;
      case OccupancyKernel::kIntegrateSpans:
        k = span_kernel_.get();
        ok = setSpanArgs(k, b, b.rays.get(), b.spans.get(), b.groups.get(), b.hit_rays.get(),
                         layerOr(map().occupancyLayer()), layerOr(map().scanMarkLayer()),
                         b.scratch.get(), layerOr(map().traversalLayer()),
                         layerOr(map().tsdfLayer()), p, b.counters.get());
        return ok && enqueueSpans(k, p.item_count);
      case OccupancyKernel::kApplyHitGroups:
        k = hit_kernel_.get();
        ok = setArgs(k, b.rays.get(), b.groups.get(), b.hit_rays.get(),
                     layerOr(map().occupancyLayer()), layerOr(map().meanLayer()),
                     layerOr(map().scanMarkLayer()), b.scratch.get(), p, b.counters.get());
        break;
    }
    return ok && enqueue(k, p.item_count);
  }

  bool launchNdt(NdtKernel kernel, unsigned set, const rm_integrate_params& p,
                 const rm_ndt_params& ndt) noexcept override {
    const DeviceBatch& b = batches_[set];
    const VoxelMap& m = map();
    cl_kernel k = nullptr;
    bool ok = false;
    switch (kernel) {
      case NdtKernel::kIntegrateSpans:
        k = span_kernel_.get();
        ok = setSpanArgs(k, b, b.rays.get(), b.spans.get(), layerOr(m.occupancyLayer()),
                         layerOr(m.ndtLayer()), layerOr(m.meanLayer()), layerOr(m.hitMissLayer()),
                         layerOr(m.traversalLayer()), p, ndt, b.counters.get());
        return ok && enqueueSpans(k, p.item_count);
      case NdtKernel::kApplyHitGroups:
        k = hit_kernel_.get();
        ok = setArgs(k, b.rays.get(), b.groups.get(), b.hit_rays.get(), layerOr(m.occupancyLayer()),
                     layerOr(m.ndtLayer()), layerOr(m.hitMissLayer()), layerOr(m.intensityLayer()),
                     layerOr(m.meanLayer()), p, ndt, b.counters.get());
        break;
    }
    return ok && enqueue(k, p.item_count);
  }

  /// Enqueues `k` over `items` work-items, rounded up to whole work-groups.
  bool enqueue(cl_kernel k, std::uint32_t items) noexcept {
    const std::size_t local = local_size_;
    const std::size_t global = (items + local - 1) / local * local;
    return clEnqueueNDRangeKernel(ctx_.queue.get(), k, 1, nullptr, &global, &local, 0, nullptr,
                                  nullptr) == CL_SUCCESS;
  }

  /// Enqueues the span kernel: over `items` span records, or, with span work per region, as a
  /// few work-items per compute unit, each its own work-group, which take the regions' runs from
  /// a shared cursor until none is left (the kernel's loop).
  bool enqueueSpans(cl_kernel k, std::uint32_t items) noexcept {
    if (!spansByRegion()) {
      return enqueue(k, items);
    }
    const std::size_t local = 1;
    const std::size_t global =
        kRegionWorkersPerUnit * std::max<std::size_t>(ctx_.info.compute_units, 1);
    return clEnqueueNDRangeKernel(ctx_.queue.get(), k, 1, nullptr, &global, &local, 0, nullptr,
                                  nullptr) == CL_SUCCESS;
  }

  bool endBatch(unsigned set) noexcept override {
    DeviceBatch& b = batches_[set];
    cl_event done = nullptr;
    if (clEnqueueReadBuffer(ctx_.queue.get(), b.counters.get(), CL_FALSE, 0, counterBytes(),
                            b.counters_host.data(), 0, nullptr, &done) != CL_SUCCESS) {
      return false;
    }
    b.done = opencl::EventHandle(done);
    (void)clFlush(ctx_.queue.get());  // start the device now; the host goes on planning
    return true;
  }

  const void* waitForBatch(unsigned set) noexcept override {
    DeviceBatch& b = batches_[set];
    const cl_event event = b.done.get();
    const cl_int status = event != nullptr ? clWaitForEvents(1, &event) : CL_INVALID_EVENT;
    b.done.reset();
    return status == CL_SUCCESS ? b.counters_host.data() : nullptr;
  }

  /// Neither direction blocks: `host` is the staging ring, untouched until the device is past
  /// the copy (gpu::TransferStaging); the in-order queue orders it with the kernels.
  bool copyLayer(int layer, std::size_t device_offset, std::byte* host, std::size_t bytes,
                 bool to_device) noexcept override {
    cl_mem buffer = layers_[static_cast<std::size_t>(layer)].get();
    return (to_device ? clEnqueueWriteBuffer(ctx_.queue.get(), buffer, CL_FALSE, device_offset,
                                             bytes, host, 0, nullptr, nullptr)
                      : clEnqueueReadBuffer(ctx_.queue.get(), buffer, CL_FALSE, device_offset,
                                            bytes, host, 0, nullptr, nullptr)) == CL_SUCCESS;
  }

  bool fillLayer(int layer, std::size_t device_offset, std::size_t bytes,
                 const LayerSpec& spec) noexcept override {
    // OpenCL fills with patterns of 1 to 128 bytes, powers of two only: a voxel of another size
    // (the 40-byte NDT voxel) whose words are all equal is filled with one word.
    std::size_t pattern_bytes = spec.bytes_per_voxel;
    if ((pattern_bytes & (pattern_bytes - 1)) != 0) {
      for (std::uint32_t w = 1; w < spec.bytes_per_voxel / 4u; ++w) {
        if (spec.clear_words[w] != spec.clear_words[0]) {
          return false;
        }
      }
      pattern_bytes = 4;
    }
    return clEnqueueFillBuffer(ctx_.queue.get(), layers_[static_cast<std::size_t>(layer)].get(),
                               spec.clear_words.data(), pattern_bytes, device_offset, bytes, 0,
                               nullptr, nullptr) == CL_SUCCESS;
  }

  bool finish() noexcept override { return clFinish(ctx_.queue.get()) == CL_SUCCESS; }

  /// Mapping a CL_MEM_USE_HOST_PTR buffer is what makes the device's writes visible in the host
  /// memory by the standard (on shared-memory devices it copies nothing).
  bool syncSharedMemory() noexcept override {
    const RegionStore& store = map().store();
    for (int l = 0; l < store.schema().size(); ++l) {
      cl_mem buffer = layers_[static_cast<std::size_t>(l)].get();
      const std::size_t bytes = store.layerRegionBytes(l) * store.capacity();
      cl_int status = CL_SUCCESS;
      void* mapped =
          clEnqueueMapBuffer(ctx_.queue.get(), buffer, CL_TRUE, CL_MAP_READ | CL_MAP_WRITE, 0,
                             bytes, 0, nullptr, nullptr, &status);
      if (status != CL_SUCCESS || clEnqueueUnmapMemObject(ctx_.queue.get(), buffer, mapped, 0,
                                                          nullptr, nullptr) != CL_SUCCESS) {
        return false;
      }
    }
    return clFinish(ctx_.queue.get()) == CL_SUCCESS;
  }

  cl_mem layerOr(int layer) const noexcept {
    return layer >= 0 ? layers_[static_cast<std::size_t>(layer)].get() : dummy_.get();
  }

  /// Sets the kernel's arguments in order (buffers as cl_mem, the parameters by value).
  template <class... Args>
  static bool setArgs(cl_kernel k, const Args&... args) noexcept {
    return setArgsFrom(k, 0, args...);
  }
  template <class... Args>
  static bool setArgsFrom(cl_kernel k, cl_uint index, const Args&... args) noexcept {
    return ((clSetKernelArg(k, index++, sizeof(Args), &args) == CL_SUCCESS) && ...);
  }
  /// The span kernel's arguments: `args`, then, with span work per region, set `b`'s runs and
  /// run cursor (the region kernels' two last parameters).
  template <class... Args>
  bool setSpanArgs(cl_kernel k, const DeviceBatch& b, const Args&... args) const noexcept {
    return setArgs(k, args...) &&
           (!spansByRegion() || setArgsFrom(k, static_cast<cl_uint>(sizeof...(Args)),
                                            b.span_runs.get(), b.next_run.get()));
  }

  opencl::DeviceContext ctx_;  // first member with handles: released last
  opencl::ProgramHandle program_;
  opencl::KernelHandle span_kernel_;
  opencl::KernelHandle hit_kernel_;
  opencl::KernelHandle tag_kernel_;        // occupancy maps with per-ray semantics only
  opencl::ProgramHandle plan_program_;     // planning on the device only
  opencl::ProgramHandle prepare_program_;  // rays prepared on the device only
  std::array<opencl::KernelHandle, gpu::kPlanKernelCount> plan_kernels_;
  std::size_t plan_group_ = 256;
  std::vector<opencl::BufferHandle> layers_;  // one per schema layer
  opencl::BufferHandle dummy_;
  std::array<DeviceBatch, kStagingSets> batches_;
  bool int64_counters_;
  std::size_t local_size_ = kWorkGroup;
  std::string program_warning_;
};

gpu::DeviceMemoryLimits memoryLimits(const opencl::DeviceInfo& device) {
  gpu::DeviceMemoryLimits limits;
  limits.device_name = device.device_name;
  limits.global_mem_bytes = device.global_mem_bytes;
  limits.max_alloc_bytes = device.max_alloc_bytes;
  limits.unified_memory = device.unified_memory;
  return limits;
}

}  // namespace

std::optional<SpanWork> spanWorkNamed(std::string_view name) noexcept {
  if (name == "auto") {
    return SpanWork::kAuto;
  }
  if (name == "span") {
    return SpanWork::kPerSpan;
  }
  if (name == "region") {
    return SpanWork::kPerRegion;
  }
  return std::nullopt;
}

opencl::BackendDevice* opencl::backendDevice(Backend& backend) noexcept {
  return dynamic_cast<OpenClBackend*>(&backend);
}

Result<std::unique_ptr<Backend>> createOpenClBackend(VoxelMap& map,
                                                     const OpenClBackendOptions& options) {
  if (map.occupancyLayer() < 0 && map.tsdfLayer() < 0 && map.traversalLayer() < 0) {
    return fail(ErrorCode::kInvalidArgument,
                "the OpenCL backend needs an occupancy, traversal or TSDF layer to integrate into");
  }
  if (auto ok = gpu::checkBatchOptions(options, "OpenCL"); !ok) {
    return Unexpected(ok.error());
  }
  auto device = opencl::findDevice(options.device);
  if (!device) {
    return Unexpected(device.error());
  }
  auto slots = gpu::deviceCacheSlots(map, memoryLimits(*device), options, "OpenCL");
  if (!slots) {
    return Unexpected(slots.error());
  }
  auto ctx = opencl::createContext(*device);
  if (!ctx) {
    return Unexpected(ctx.error());
  }
  const bool int64_counters = device->int64_atomics && !options.force_32bit_atomics;
  auto backend =
      std::make_unique<OpenClBackend>(map, std::move(*ctx), *slots, int64_counters, options);
  if (auto ok = backend->initialise(options); !ok) {
    return Unexpected(ok.error());
  }
  return std::unique_ptr<Backend>(std::move(backend));
}

}  // namespace raymap
