// SPDX-License-Identifier: BSD-3-Clause
// CUDA backend: device memory, one stream, events per batch, kernel launches. The batch loop, the
// kernel order and region moves are gpu::StagedBackend's.
#include "src/device/cuda/cuda_backend.hpp"

#include <array>
#include <cstdio>
#include <new>
#include <string>
#include <tuple>
#include <vector>

#include "kernels/common/batch.h"
#include "kernels/cuda/launch.h"
#include "kernels/cuda/ndt_launch.h"
#include "kernels/cuda/plan_launch.h"
#include "src/device/cuda/cuda_devices.hpp"
#include "src/device/cuda/cuda_handles.hpp"
#include "src/device/staging/staged_backend.hpp"

namespace raymap {
namespace {

using gpu::NdtKernel;
using gpu::OccupancyKernel;
using gpu::PlanBuffer;

/// Device buffers of one staging set, its page-locked counter read-back and its end event.
struct DeviceBatch {
  cuda::DeviceMemoryHandle rays;
  cuda::DeviceMemoryHandle spans;
  cuda::DeviceMemoryHandle groups;
  cuda::DeviceMemoryHandle hit_rays;
  cuda::DeviceMemoryHandle counters;
  cuda::DeviceMemoryHandle scratch;        // per-ray semantics: saved values and runs of misses
  cuda::PinnedMemoryHandle counters_host;  // RM_COUNTER_COUNT 64-bit words
  cuda::EventHandle done;                  // recorded after the counters' read-back
  // Planning on the device: the planner's own buffers (PlanBuffer ids) and the event recorded
  // after the plan's read-back.
  std::array<cuda::DeviceMemoryHandle, gpu::kPlanBufferCount> plan;
  cuda::EventHandle plan_read;
};

template <class T>
T* typed(const cuda::DeviceMemoryHandle& memory) noexcept {
  return static_cast<T*>(memory.get());
}

class CudaBackend final : public gpu::StagedBackend, public cuda::BackendDevice {
 public:
  /// slots == 0: shared memory (the device works on the host store in place).
  CudaBackend(VoxelMap& map, cuda::DeviceInfo device, std::uint32_t slots,
              const CudaBackendOptions& options)
      : StagedBackend(map, slots, /*wide_counters=*/true, options, cuda::pinnedHostMemory()),
        device_(std::move(device)),
        block_threads_(options.block_threads),
        plan_on_device_(options.planning == gpu::Planning::kDevice),
        prepare_on_device_(options.prepare_on_device) {}

  ~CudaBackend() override {
    if (stream_ && cudaSetDevice(device_.index) == cudaSuccess) {
      (void)cudaStreamSynchronize(stream_.get());
    }
  }

  /// Allocates device memory and page-locks host memory; called once by the factory.
  Expected<void, Error> initialise() {
    if (auto ok = checkMapIsSupported(); !ok) {
      return ok;
    }
    if (const cudaError_t s = cudaSetDevice(device_.index); s != cudaSuccess) {
      return Unexpected(cuda::cudaFailure("CUDA device " + std::to_string(device_.index), s));
    }
    auto stream = cuda::createStream();
    if (!stream) {
      return Unexpected(stream.error());
    }
    stream_ = std::move(*stream);
    auto idle = cuda::createEvent();
    if (!idle) {
      return Unexpected(idle.error());
    }
    idle_ = std::move(*idle);
    if (auto ok = allocateLayers(); !ok) {
      return ok;
    }
    auto dummy = cuda::allocateDevice(sizeof(rm_voxel_mean), "placeholder for absent layers");
    if (!dummy) {
      return Unexpected(dummy.error());
    }
    dummy_ = std::move(*dummy);
    for (unsigned set = 0; set < kStagingSets; ++set) {
      if (auto ok = allocateBatch(set); !ok) {
        return ok;
      }
    }
    if (!finish()) {
      return fail(ErrorCode::kCapacity,
                  "CUDA device region cache: initialising it failed on " + device_.name);
    }
    return plan_on_device_ ? initialisePlanning() : Expected<void, Error>{};
  }

  const char* name() const noexcept override { return "cuda"; }
  std::string deviceName() const override {
    return device_.name + " (CUDA " + std::to_string(device_.compute_major) + "." +
           std::to_string(device_.compute_minor) + ", runtime " +
           cuda::versionText(device_.runtime_version) + ")" +
           (sharedMemory() ? ", shared memory" : "") +
           (planning() == gpu::Planning::kDevice ? ", planned on the device" : "") +
           (preparesOnDevice(RayFilter{}) ? ", rays prepared on the device" : "");
  }

  // ---- cuda::BackendDevice ----
  int deviceIndex() const noexcept override { return device_.index; }
  CUstream_st* stream() const noexcept override { return stream_.get(); }
  const void* layerPointer(int layer) const noexcept override { return layerOr(layer); }
  gpu::StagedBackend& staged() noexcept override { return *this; }

 private:
  /// One allocation per map layer: cache slots in device memory, or (shared memory) the host
  /// store's array, page-locked and mapped.
  Expected<void, Error> allocateLayers() {
    const RegionStore& store = map().store();
    const LayerSchema& schema = store.schema();
    if (sharedMemory()) {
      return mapHostStore();
    }
    layers_.resize(static_cast<std::size_t>(schema.size()));
    for (int l = 0; l < schema.size(); ++l) {
      const auto index = static_cast<std::size_t>(l);
      const std::size_t bytes = store.layerRegionBytes(l) * layerRegions();
      const std::string layer_name(schema.at(l).name);
      auto memory = cuda::allocateDevice(bytes, "device region cache, layer '" + layer_name + "'");
      if (!memory) {
        return Unexpected(memory.error());
      }
      layers_[index] = std::move(*memory);
      layer_ptrs_.push_back(layers_[index].get());
      // Clear all of the cache now, at start-up, so integration never meets uninitialised memory
      // or first-touch costs.
      if (!fillLayer(l, 0, bytes, schema.at(l))) {
        return fail(ErrorCode::kCapacity, "CUDA device region cache, layer '" + layer_name +
                                              "': cannot initialise " + std::to_string(bytes) +
                                              " bytes on " + device_.name);
      }
    }
    return {};
  }

  /// Shared memory: the store's layers lie one after the other in one pool, so the pool is
  /// page-locked and mapped once (layers need not start on page boundaries, and a page can be
  /// registered only once), and each layer's device address is taken inside it.
  Expected<void, Error> mapHostStore() {
    const RegionStore& store = map().store();
    const int last = store.schema().size() - 1;
    std::byte* begin = store.layerBytes(0, 0);
    std::byte* end = store.layerBytes(0, last) + store.layerRegionBytes(last) * store.capacity();
    auto pinned = cuda::HostRegistration::create(begin, static_cast<std::size_t>(end - begin),
                                                 cudaHostRegisterMapped, "the map's region pool");
    if (!pinned) {
      return Unexpected(pinned.error());
    }
    shared_store_ = std::move(*pinned);
    for (int l = 0; l <= last; ++l) {
      void* device_ptr = nullptr;
      if (const cudaError_t s = cudaHostGetDevicePointer(&device_ptr, store.layerBytes(0, l), 0);
          s != cudaSuccess) {
        return Unexpected(cuda::cudaFailure(
            "mapping the map's layer '" + std::string(store.schema().at(l).name) + "'", s));
      }
      layer_ptrs_.push_back(device_ptr);
    }
    return {};
  }

  /// Device buffers of one staging set (its host arrays are the base class's, in page-locked
  /// memory from cuda::pinnedHostMemory()).
  Expected<void, Error> allocateBatch(unsigned set) {
    DeviceBatch& b = batches_[set];
    const gpu::BatchLimits& limits = this->limits();
    for (auto [handle, bytes, what] :
         {std::tuple{&b.rays, limits.max_rays * sizeof(PreparedRay), "ray batch"},
          std::tuple{&b.spans, limits.max_spans * sizeof(rm_span_record), "span batch"},
          std::tuple{&b.groups, limits.max_rays * sizeof(rm_hit_group), "hit groups"},
          std::tuple{&b.hit_rays, limits.max_rays * sizeof(std::uint32_t), "hit list"},
          std::tuple{&b.counters, counterBytes(), "counters"},
          std::tuple{&b.scratch, scratchWords() * 4u, "batch scratch"}}) {
      auto memory = cuda::allocateDevice(bytes, what);
      if (!memory) {
        return Unexpected(memory.error());
      }
      *handle = std::move(*memory);
    }
    void* host = nullptr;
    if (const cudaError_t s = cudaMallocHost(&host, counterBytes()); s != cudaSuccess) {
      (void)cudaGetLastError();  // a later launch's check must not see this failure as its own
      return Unexpected(cuda::cudaFailure("CUDA counter read-back buffer", s));
    }
    b.counters_host.reset(host);
    auto event = cuda::createEvent();
    if (!event) {
      return Unexpected(event.error());
    }
    b.done = std::move(*event);
    return {};
  }

  /// True when `status` is success. Otherwise the CUDA call named `what` failed: the staged
  /// backend turns that into IntegrateError::kDeviceFailure without a cause, so the first few
  /// failures of a backend are also written to stderr with CUDA's name for the error (a kernel
  /// fault is sticky: every later call fails the same way). Failure path only: the steady state
  /// writes nothing.
  bool succeeded(cudaError_t status, const char* what) noexcept {
    if (status == cudaSuccess) {
      return true;
    }
    if (failures_reported_ < kFailuresReported) {
      ++failures_reported_;
      std::fprintf(stderr, "raymap: CUDA %s on device %d failed: %s (%s)\n", what, device_.index,
                   cudaGetErrorName(status), cudaGetErrorString(status));
    }
    return false;
  }

  /// Each set's planning buffers (the kernels are kernels/cuda/plan.cu, blocks of
  /// RM_PLAN_GROUP threads).
  Expected<void, Error> initialisePlanning() {
    auto sizes = devicePlanSizesFor(RM_PLAN_GROUP);
    if (!sizes) {
      return Unexpected(sizes.error());
    }
    sizes->prepare = prepare_on_device_;  // every CUDA device has double precision
    for (DeviceBatch& set : batches_) {
      for (std::size_t id = 0; id < gpu::kPlanBufferCount; ++id) {
        const std::size_t bytes = sizes->bytes(static_cast<PlanBuffer>(id));
        if (bytes == 0) {
          continue;
        }
        auto memory = cuda::allocateDevice(bytes, "device planning");
        if (!memory) {
          return Unexpected(memory.error());
        }
        set.plan[id] = std::move(*memory);
      }
      auto event = cuda::createEvent();
      if (!event) {
        return Unexpected(event.error());
      }
      set.plan_read = std::move(*event);
    }
    return planOnDevice(*sizes);
  }

  /// The device buffer a planning kernel's argument `id` names on set `set` (nullptr: none).
  std::uint32_t* planBuffer(unsigned set, PlanBuffer id) const noexcept {
    const DeviceBatch& b = batches_[set];
    switch (id) {
      case PlanBuffer::kNone:
      case PlanBuffer::kRegionSpans:  // CUDA has only span work per span record
      case PlanBuffer::kSpanRuns:
        return nullptr;
      case PlanBuffer::kRays:
        return typed<std::uint32_t>(b.rays);
      case PlanBuffer::kSpans:
        return typed<std::uint32_t>(b.spans);
      case PlanBuffer::kGroups:
        return typed<std::uint32_t>(b.groups);
      case PlanBuffer::kHitRays:
        return typed<std::uint32_t>(b.hit_rays);
      default:
        return typed<std::uint32_t>(b.plan[static_cast<std::size_t>(id)]);
    }
  }

  // ---- gpu::PlanDevice ----
  bool launchPlan(unsigned set, const gpu::PlanLaunch& launch) noexcept override {
    std::uint32_t* buffers[RM_PLAN_BUFFERS] = {};
    for (std::size_t i = 0; i < RM_PLAN_BUFFERS; ++i) {
      buffers[i] = planBuffer(set, launch.buffers[i]);
    }
    return succeeded(cuda::launchPlanKernel(static_cast<unsigned>(launch.kernel), stream_.get(),
                                            launch.items, launch.args, buffers),
                     gpu::planKernelName(launch.kernel));
  }

  bool writePlanBuffer(unsigned set, PlanBuffer buffer, std::size_t offset, const void* host,
                       std::size_t bytes) noexcept override {
    return bytes == 0 ||
           succeeded(cudaMemcpyAsync(reinterpret_cast<std::byte*>(planBuffer(set, buffer)) + offset,
                                     host, bytes, cudaMemcpyHostToDevice, stream_.get()),
                     "planning upload");
  }

  bool readPlanBuffer(unsigned set, PlanBuffer buffer, std::size_t offset, void* host,
                      std::size_t bytes) noexcept override {
    return bytes == 0 ||
           succeeded(
               cudaMemcpyAsync(host, reinterpret_cast<std::byte*>(planBuffer(set, buffer)) + offset,
                               bytes, cudaMemcpyDeviceToHost, stream_.get()),
               "planning read-back");
  }

  bool markPlanRead(unsigned set) noexcept override {
    return succeeded(cudaEventRecord(batches_[set].plan_read.get(), stream_.get()),
                     "planning event record");
  }

  bool waitPlanRead(unsigned set) noexcept override {
    return succeeded(cudaEventSynchronize(batches_[set].plan_read.get()), "planning read-back");
  }

  // ---- gpu::StagedBackend ----
  bool makeCurrent() noexcept override {
    return succeeded(cudaSetDevice(device_.index), "cudaSetDevice");
  }

  bool uploadBatch(unsigned set, const gpu::BatchArrays* arrays) noexcept override {
    const DeviceBatch& b = batches_[set];
    bool ok = true;
    auto copy = [&](const cuda::DeviceMemoryHandle& dst, const void* src, std::size_t bytes) {
      ok = ok && (bytes == 0 || succeeded(cudaMemcpyAsync(dst.get(), src, bytes,
                                                          cudaMemcpyHostToDevice, stream_.get()),
                                          "batch upload"));
    };
    if (arrays != nullptr) {
      const gpu::BatchArrays& a = *arrays;
      copy(b.rays, a.rays.data(), a.rays.size() * sizeof(PreparedRay));
      copy(b.spans, a.spans.data(), a.spans.size() * sizeof(rm_span_record));
      copy(b.groups, a.groups.data(), a.groups.size() * sizeof(rm_hit_group));
      copy(b.hit_rays, a.hit_rays.data(), a.hit_rays.size() * sizeof(std::uint32_t));
    }
    return ok && succeeded(cudaMemsetAsync(b.counters.get(), 0, counterBytes(), stream_.get()),
                           "counter reset");
  }

  bool clearScratch(unsigned set, std::size_t first_word, std::size_t words) noexcept override {
    return succeeded(cudaMemsetAsync(typed<std::uint32_t>(batches_[set].scratch) + first_word, 0,
                                     words * 4u, stream_.get()),
                     "scratch clear");
  }

  bool launch(OccupancyKernel kernel, unsigned set,
              const rm_integrate_params& p) noexcept override {
    const DeviceBatch& b = batches_[set];
    cuda::OccupancyKernelBuffers buffers;
    buffers.rays = typed<const rm_prepared_ray>(b.rays);
    buffers.spans = typed<const rm_span_record>(b.spans);
    buffers.groups = typed<const rm_hit_group>(b.groups);
    buffers.hit_rays = typed<const std::uint32_t>(b.hit_rays);
    buffers.occupancy = static_cast<std::uint32_t*>(layerOr(map().occupancyLayer()));
    buffers.means = static_cast<rm_voxel_mean*>(layerOr(map().meanLayer()));
    buffers.marks = static_cast<std::uint32_t*>(layerOr(map().scanMarkLayer()));
    buffers.scratch = typed<std::uint32_t>(b.scratch);
    buffers.traversal = static_cast<std::uint32_t*>(layerOr(map().traversalLayer()));
    buffers.tsdf = static_cast<std::uint32_t*>(layerOr(map().tsdfLayer()));
    buffers.counters = typed<unsigned long long>(b.counters);
    const cuda::OccupancyKernelId id =
        kernel == OccupancyKernel::kTagHitGroups     ? cuda::OccupancyKernelId::kTagHitGroups
        : kernel == OccupancyKernel::kIntegrateSpans ? cuda::OccupancyKernelId::kIntegrateSpans
                                                     : cuda::OccupancyKernelId::kApplyHitGroups;
    return succeeded(
        cuda::launchOccupancyKernel(id, mapMode(), stream_.get(), block_threads_, buffers, p),
        "occupancy kernel launch");
  }

  bool launchNdt(NdtKernel kernel, unsigned set, const rm_integrate_params& p,
                 const rm_ndt_params& ndt) noexcept override {
    const DeviceBatch& b = batches_[set];
    const VoxelMap& m = map();
    cuda::NdtKernelBuffers buffers;
    buffers.rays = typed<const rm_prepared_ray>(b.rays);
    buffers.spans = typed<const rm_span_record>(b.spans);
    buffers.groups = typed<const rm_hit_group>(b.groups);
    buffers.hit_rays = typed<const std::uint32_t>(b.hit_rays);
    buffers.occupancy = static_cast<std::uint32_t*>(layerOr(m.occupancyLayer()));
    buffers.ndt = static_cast<rm_ndt_voxel*>(layerOr(m.ndtLayer()));
    buffers.hit_miss = static_cast<rm_ndt_hit_miss*>(layerOr(m.hitMissLayer()));
    buffers.intensity = static_cast<rm_ndt_intensity*>(layerOr(m.intensityLayer()));
    buffers.means = static_cast<rm_voxel_mean*>(layerOr(m.meanLayer()));
    buffers.traversal = static_cast<std::uint32_t*>(layerOr(m.traversalLayer()));
    buffers.counters = typed<unsigned long long>(b.counters);
    const cuda::NdtKernelId id = kernel == NdtKernel::kIntegrateSpans
                                     ? cuda::NdtKernelId::kIntegrateSpans
                                     : cuda::NdtKernelId::kApplyHitGroups;
    return succeeded(
        cuda::launchNdtKernel(id, mapMode(), stream_.get(), block_threads_, buffers, p, ndt),
        "NDT kernel launch");
  }

  bool endBatch(unsigned set) noexcept override {
    DeviceBatch& b = batches_[set];
    return succeeded(cudaMemcpyAsync(b.counters_host.get(), b.counters.get(), counterBytes(),
                                     cudaMemcpyDeviceToHost, stream_.get()),
                     "counter read-back") &&
           succeeded(cudaEventRecord(b.done.get(), stream_.get()), "batch event record");
  }

  const void* waitForBatch(unsigned set) noexcept override {
    DeviceBatch& b = batches_[set];
    // A fault inside a kernel of the batch surfaces here.
    return succeeded(cudaEventSynchronize(b.done.get()), "batch (kernels and read-back)")
               ? b.counters_host.get()
               : nullptr;
  }

  /// `host` is the staging ring in page-locked memory (gpu::TransferStaging), untouched until
  /// the stream is past the copy: both directions are asynchronous DMA, nothing waits.
  bool copyLayer(int layer, std::size_t device_offset, std::byte* host, std::size_t bytes,
                 bool to_device) noexcept override {
    std::byte* device =
        static_cast<std::byte*>(layer_ptrs_[static_cast<std::size_t>(layer)]) + device_offset;
    if (to_device) {
      return succeeded(cudaMemcpyAsync(device, host, bytes, cudaMemcpyHostToDevice, stream_.get()),
                       "region upload");
    }
    return succeeded(cudaMemcpyAsync(host, device, bytes, cudaMemcpyDeviceToHost, stream_.get()),
                     "region download");
  }

  bool fillLayer(int layer, std::size_t device_offset, std::size_t bytes,
                 const LayerSpec& spec) noexcept override {
    cuda::FillPattern pattern;
    pattern.count = spec.bytes_per_voxel / 4u;
    for (unsigned w = 0; w < pattern.count && w < LayerSpec::kMaxWordsPerVoxel; ++w) {
      pattern.words[w] = spec.clear_words[w];
    }
    auto* device = static_cast<std::uint32_t*>(layer_ptrs_[static_cast<std::size_t>(layer)]) +
                   device_offset / 4u;
    return succeeded(cuda::launchFill(stream_.get(), device, bytes / 4u, pattern),
                     "layer fill launch");
  }

  /// Waits on an event rather than the stream, so the host thread sleeps instead of spinning.
  bool finish() noexcept override {
    return succeeded(cudaEventRecord(idle_.get(), stream_.get()), "idle event record") &&
           succeeded(cudaEventSynchronize(idle_.get()), "device work");
  }

  void* layerOr(int layer) const noexcept {
    return layer >= 0 ? layer_ptrs_[static_cast<std::size_t>(layer)] : dummy_.get();
  }

  cuda::DeviceInfo device_;
  unsigned block_threads_;
  bool plan_on_device_;
  bool prepare_on_device_;
  cuda::StreamHandle stream_;
  cuda::EventHandle idle_;
  std::vector<cuda::DeviceMemoryHandle> layers_;  // cache mode: one per schema layer
  cuda::HostRegistration shared_store_;  // shared memory: the host store, page-locked and mapped
  std::vector<void*> layer_ptrs_;        // device address of each layer
  cuda::DeviceMemoryHandle dummy_;
  std::array<DeviceBatch, kStagingSets> batches_;
  static constexpr unsigned kFailuresReported = 8;
  unsigned failures_reported_ = 0;
};

gpu::DeviceMemoryLimits memoryLimits(const cuda::DeviceInfo& device,
                                     const CudaBackendOptions& options) {
  gpu::DeviceMemoryLimits limits;
  limits.device_name = device.name;
  limits.global_mem_bytes = device.global_mem_bytes;
  limits.max_alloc_bytes = device.global_mem_bytes;  // CUDA has no per-allocation limit
  // A discrete GPU reaches mapped host memory across the bus: only where asked (tests).
  limits.unified_memory = device.integrated || (options.map_host_memory_on_discrete &&
                                                options.memory == DeviceMemory::kShared);
  limits.can_map_host_memory = device.can_map_host_memory;
  return limits;
}

}  // namespace

cuda::BackendDevice* cuda::backendDevice(Backend& backend) noexcept {
  return dynamic_cast<CudaBackend*>(&backend);
}

Result<std::unique_ptr<Backend>> createCudaBackend(VoxelMap& map,
                                                   const CudaBackendOptions& options) {
  if (map.occupancyLayer() < 0 && map.tsdfLayer() < 0 && map.traversalLayer() < 0) {
    return fail(ErrorCode::kInvalidArgument,
                "the CUDA backend needs an occupancy, traversal or TSDF layer to integrate into");
  }
  if (auto ok = gpu::checkBatchOptions(options, "CUDA"); !ok) {
    return Unexpected(ok.error());
  }
  if (auto ok = cuda::checkBlockThreads(options.block_threads); !ok) {
    return Unexpected(ok.error());
  }
  auto device = cuda::findDevice(options.device);
  if (!device) {
    return Unexpected(device.error());
  }
  auto slots = gpu::deviceCacheSlots(map, memoryLimits(*device, options), options, "CUDA");
  if (!slots) {
    return Unexpected(slots.error());
  }
  // The device is current before anything of it is allocated (the staging arrays are, in the
  // constructor).
  if (const cudaError_t s = cudaSetDevice(device->index); s != cudaSuccess) {
    return Unexpected(cuda::cudaFailure("CUDA device " + std::to_string(device->index), s));
  }
  std::unique_ptr<CudaBackend> backend;
  try {
    backend = std::make_unique<CudaBackend>(map, std::move(*device), *slots, options);
  } catch (const std::bad_alloc&) {
    return fail(ErrorCode::kCapacity,
                "CUDA batch staging: cannot allocate page-locked host memory for batches of " +
                    std::to_string(options.batch_rays) + " rays; lower queues.batch_rays");
  }
  if (auto ok = backend->initialise(); !ok) {
    return Unexpected(ok.error());
  }
  return std::unique_ptr<Backend>(std::move(backend));
}

}  // namespace raymap
