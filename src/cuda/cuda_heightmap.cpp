// SPDX-License-Identifier: BSD-3-Clause
#include "src/cuda/cuda_heightmap.hpp"

#include <algorithm>
#include <string>
#include <utility>
#include <vector>

#include "kernels/cuda/heightmap_launch.h"
#include "src/cuda/cuda_devices.hpp"
#include "src/cuda/cuda_handles.hpp"
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
  CudaHeightmapGenerator(cuda::DeviceInfo device, cuda::StreamHandle stream, unsigned block)
      : device_(std::move(device)), stream_(std::move(stream)), block_threads_(block) {}
  ~CudaHeightmapGenerator() override {
    if (stream_) {
      (void)cudaStreamSynchronize(stream_.get());
    }
  }

  const char* name() const noexcept override { return "cuda"; }
  std::uint64_t bytesCopied() const noexcept override { return bytes_copied_; }
  std::string deviceName() const override { return device_.name; }

  Expected<void, Error> generate(const VoxelMap& map, const heightmap::HeightmapPlan& plan,
                                 heightmap::HeightMap& out) override {
    using namespace heightmap;
    prepareOutput(plan, out);
    if (const cudaError_t s = cudaSetDevice(device_.index); s != cudaSuccess) {
      return Unexpected(cuda::cudaFailure("CUDA height map: selecting the device", s));
    }
    upload_.prepare(map, plan);
    for (std::size_t b = 0; b < kDeviceBufferCount; ++b) {
      if (auto ok = reserve(buffers_[b], upload_.bytes[b], static_cast<DeviceBuffer>(b)); !ok) {
        return ok;
      }
    }
    cudaStream_t s = stream_.get();
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
    k.occupancy = buffers_[kOccupancyBuffer].as<const float>();
    k.masks = buffers_[kMasksBuffer].as<rm_hm_mask>();
    k.mean = buffers_[kMeanBuffer].as<const rm_voxel_mean>();
    k.ndt = buffers_[kNdtBuffer].as<const rm_ndt_voxel>();
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
    bytes_copied_ += upload_.copiedBytes(plan, out);
    return {};
  }

 private:
  Expected<void, Error> reserve(GrowingBuffer& buffer, std::size_t bytes,
                                heightmap::DeviceBuffer what) {
    if (buffer.memory && buffer.bytes >= bytes) {
      return {};
    }
    (void)cudaStreamSynchronize(stream_.get());
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

  cuda::DeviceInfo device_;
  cuda::StreamHandle stream_;
  unsigned block_threads_;
  GrowingBuffer buffers_[heightmap::kDeviceBufferCount];
  heightmap::DeviceUpload upload_;
  std::uint64_t bytes_copied_ = 0;  // host <-> device by every generation
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

}  // namespace raymap
