// SPDX-License-Identifier: BSD-3-Clause
#include "src/device/cuda/cuda_heightmap.hpp"

#include <algorithm>
#include <string>
#include <utility>
#include <vector>

#include "kernels/cuda/heightmap_launch.h"
#include "src/device/cuda/cuda_backend.hpp"
#include "src/device/cuda/cuda_devices.hpp"
#include "src/device/cuda/cuda_handles.hpp"
#include "src/device/staging/resident_read.hpp"
#include "src/heightmap/device_upload.hpp"

namespace raymap {
namespace {

/// A device allocation that grows on demand.
struct GrowingBuffer {
  cuda::DeviceMemoryHandle memory;
  std::size_t bytes = 0;
  template <class T>
  T* as() const noexcept {
    return static_cast<T*>(memory.get());
  }
};

class CudaHeightmapGenerator final : public heightmap::HeightmapGenerator {
 public:
  /// Standalone: its own stream, reading the host store.
  CudaHeightmapGenerator(cuda::DeviceInfo device, cuda::StreamHandle stream, unsigned block)
      : device_(std::move(device)),
        owned_stream_(std::move(stream)),
        stream_(owned_stream_.get()),
        block_threads_(block) {}
  /// On `backend`'s stream, reading the layers where it left them.
  CudaHeightmapGenerator(cuda::DeviceInfo device, cuda::BackendDevice& backend, unsigned block)
      : device_(std::move(device)),
        stream_(backend.stream()),
        backend_(&backend),
        block_threads_(block) {}
  ~CudaHeightmapGenerator() override {
    // The backend's stream is the backend's to drain (generate() returns with it idle anyway).
    if (owned_stream_ && cudaSetDevice(device_.index) == cudaSuccess) {
      (void)cudaStreamSynchronize(owned_stream_.get());
    }
  }

  const char* name() const noexcept override { return "cuda"; }
  std::uint64_t bytesCopied() const noexcept override { return upload_.total_bytes; }
  std::uint64_t mapBytesCopied() const noexcept override { return upload_.total_map_bytes; }
  bool readsHostStore() const noexcept override { return backend_ == nullptr; }
  std::string deviceName() const override { return device_.name; }

  Expected<void, Error> generate(const VoxelMap& map, const heightmap::HeightmapPlan& plan,
                                 heightmap::HeightMap& out) override {
    using namespace heightmap;
    prepareOutput(plan, out);
    if (const cudaError_t s = cudaSetDevice(device_.index); s != cudaSuccess) {
      return Unexpected(cuda::cudaFailure("CUDA height map: selecting the device", s));
    }
    auto slots = resident_.prepare(backend_ == nullptr ? nullptr : &backend_->staged(), map,
                                   plan.region_slots, "CUDA");
    if (!slots) {
      return Unexpected(slots.error());
    }
    upload_.prepare(map, plan, *slots);
    upload_.countResidencyUploads(resident_.bytesUploaded());
    for (std::size_t b = 0; b < kDeviceBufferCount; ++b) {
      if (auto ok = reserve(buffers_[b], upload_.bytes[b], static_cast<DeviceBuffer>(b)); !ok) {
        return ok;
      }
    }
    cudaStream_t s = stream_;
    cudaError_t status = cudaSuccess;
    upload_.forEachCopy(
        map, plan,
        [&](DeviceBuffer buffer, std::size_t offset, const void* data, std::size_t bytes) {
          if (status == cudaSuccess) {
            status = cudaMemcpyAsync(buffers_[buffer].as<std::byte>() + offset, data, bytes,
                                     cudaMemcpyHostToDevice, s);
          }
        });
    if (status != cudaSuccess) {
      return Unexpected(cuda::cudaFailure("CUDA height map: uploading the map regions", status));
    }
    cuda::HeightmapKernelBuffers k;
    k.table = buffers_[kTableBuffer].as<const std::uint32_t>();
    k.region_slots = buffers_[kRegionSlotsBuffer].as<const std::uint32_t>();
    k.occupancy = static_cast<const float*>(mapLayer(kOccupancyBuffer));
    k.masks = buffers_[kMasksBuffer].as<rm_hm_mask>();
    k.mean = static_cast<const rm_voxel_mean*>(mapLayer(kMeanBuffer));
    k.ndt = static_cast<const rm_ndt_voxel*>(mapLayer(kNdtBuffer));
    k.elevation = buffers_[kElevationBuffer].as<float>();
    k.clearance = buffers_[kClearanceBuffer].as<float>();
    k.kind = buffers_[kKindBuffer].as<std::uint32_t>();
    k.samples = buffers_[kObservedCountBuffer].as<std::uint32_t>();
    k.reference = buffers_[kReferenceBuffer].as<float>();
    k.normal_x = buffers_[kNormalXBuffer].as<float>();
    k.normal_y = buffers_[kNormalYBuffer].as<float>();
    k.normal_z = buffers_[kNormalZBuffer].as<float>();
    const rm_heightmap_params& p = plan.params;
    status = cuda::launchHeightmapMasks(s, block_threads_, k, p,
                                        static_cast<std::uint32_t>(plan.region_slots.size()));
    if (status == cudaSuccess && (p.flags & RM_HM_FLAG_FILL) != 0) {
      const rm_i32 rings = rm_hm_ring_count(p);
      for (rm_i32 ring = 0; ring < rings && status == cudaSuccess; ++ring) {
        status = cuda::launchHeightmapFillRing(s, block_threads_, k, p, ring);
      }
    } else if (status == cudaSuccess) {
      status = cuda::launchHeightmapPlanar(s, block_threads_, k, p);
    }
    if (status != cudaSuccess) {
      return Unexpected(cuda::cudaFailure("CUDA height map: launching the kernel", status));
    }
    DeviceUpload::forEachOutput(out, [&](DeviceBuffer buffer, void* target) {
      if (status == cudaSuccess) {
        status = cudaMemcpyAsync(target, buffers_[buffer].memory.get(), out.cellCount() * 4,
                                 cudaMemcpyDeviceToHost, s);
      }
    });
    if (status == cudaSuccess) {
      status = cudaStreamSynchronize(s);
    }
    if (status != cudaSuccess) {
      return Unexpected(cuda::cudaFailure("CUDA height map: reading the layers back", status));
    }
    upload_.countGeneration(plan, out);
    return {};
  }

 private:
  Expected<void, Error> reserve(GrowingBuffer& buffer, std::size_t bytes,
                                heightmap::DeviceBuffer what) {
    if (buffer.memory && buffer.bytes >= bytes) {
      return {};
    }
    (void)cudaStreamSynchronize(stream_);
    buffer.memory.reset();
    buffer.bytes = 0;
    auto memory =
        cuda::allocateDevice(bytes, std::string("CUDA height map: ") + heightmap::toString(what));
    if (!memory) {
      return Unexpected(memory.error());
    }
    buffer.memory = std::move(*memory);
    buffer.bytes = bytes;
    return {};
  }

  /// A map layer's device address: the backend's layer where resident, else the uploaded copy.
  const void* mapLayer(heightmap::DeviceBuffer buffer) const noexcept {
    return upload_.resident
               ? backend_->layerPointer(upload_.layerOf(buffer, backend_->staged().integratedMap()))
               : buffers_[buffer].memory.get();
  }

  cuda::DeviceInfo device_;
  cuda::StreamHandle owned_stream_;  // standalone only
  cudaStream_t stream_;
  cuda::BackendDevice* backend_ = nullptr;  // on the backend's stream: it outlives this
  unsigned block_threads_;
  GrowingBuffer buffers_[heightmap::kDeviceBufferCount];
  heightmap::DeviceUpload upload_;
  gpu::ResidentRead resident_;
};

}  // namespace

Result<std::unique_ptr<heightmap::HeightmapGenerator>> createCudaHeightmapGenerator(
    const CudaHeightmapOptions& options) {
  if (auto ok = cuda::checkBlockThreads(options.block_threads); !ok) {
    return Unexpected(ok.error());
  }
  auto device = cuda::findDevice(options.device);
  if (!device) {
    return Unexpected(device.error());
  }
  if (const cudaError_t s = cudaSetDevice(device->index); s != cudaSuccess) {
    return Unexpected(cuda::cudaFailure("CUDA device " + std::to_string(device->index), s));
  }
  auto stream = cuda::createStream();
  if (!stream) {
    return Unexpected(stream.error());
  }
  return std::unique_ptr<heightmap::HeightmapGenerator>(std::make_unique<CudaHeightmapGenerator>(
      std::move(*device), std::move(*stream), options.block_threads));
}

Result<std::unique_ptr<heightmap::HeightmapGenerator>> createCudaHeightmapGenerator(
    Backend& backend, unsigned block_threads) {
  if (auto ok = cuda::checkBlockThreads(block_threads); !ok) {
    return Unexpected(ok.error());
  }
  cuda::BackendDevice* shared = cuda::backendDevice(backend);
  if (shared == nullptr) {
    return fail(ErrorCode::kInvalidArgument,
                std::string("a CUDA height-map generator cannot share the device state of the ") +
                    backend.name() + " backend");
  }
  auto device = cuda::findDevice(shared->deviceIndex());
  if (!device) {
    return Unexpected(device.error());
  }
  return std::unique_ptr<heightmap::HeightmapGenerator>(
      std::make_unique<CudaHeightmapGenerator>(std::move(*device), *shared, block_threads));
}

}  // namespace raymap
