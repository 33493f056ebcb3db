// SPDX-License-Identifier: BSD-3-Clause
#include "src/cuda/cuda_heightmap.hpp"

#include <algorithm>
#include <string>
#include <tuple>
#include <vector>

#include "kernels/cuda/heightmap_launch.h"
#include "src/cuda/cuda_devices.hpp"
#include "src/cuda/cuda_handles.hpp"

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
  std::string deviceName() const override { return device_.name; }

  Expected<void, Error> generate(const VoxelMap& map, const heightmap::HeightmapPlan& plan,
                                 heightmap::HeightMap& out) override {
    heightmap::prepareOutput(plan, out);
    if (const cudaError_t s = cudaSetDevice(device_.index); s != cudaSuccess) {
      return Unexpected(cuda::cudaFailure("CUDA height map: selecting the device", s));
    }
    const RegionStore& store = map.store();
    const int occupancy_layer = map.occupancyLayer();
    const int mean_layer = map.meanLayer();
    const bool with_mean = (plan.params.flags & RM_HM_FLAG_MEAN) != 0 && mean_layer >= 0;

    // Regions are uploaded in the plan's region order, so region r sits in slot r on the device.
    const std::vector<std::uint32_t>& slots = plan.region_slots;
    identity_.resize(std::max<std::size_t>(slots.size(), 1));
    for (std::size_t r = 0; r < identity_.size(); ++r) {
      identity_[r] = static_cast<std::uint32_t>(r);
    }
    const std::size_t regions = identity_.size();
    const auto plane = static_cast<std::size_t>(plan.params.region_voxels) *
                       static_cast<std::size_t>(plan.params.region_voxels);
    const std::size_t mask_bytes =
        regions * plane * static_cast<std::size_t>(rm_hm_mask_words(plan.params.region_voxels)) *
        sizeof(rm_hm_mask);
    const std::size_t occupancy_bytes = store.layerRegionBytes(occupancy_layer);
    const std::size_t mean_bytes = with_mean ? store.layerRegionBytes(mean_layer) : 0;
    const std::size_t cells = out.cellCount();
    for (auto [buffer, bytes, what] :
         {std::tuple{&table_, plan.region_table.size() * 4, "region table"},
          std::tuple{&region_slots_, regions * 4, "region slots"},
          std::tuple{&masks_, mask_bytes, "column masks"},
          std::tuple{&occupancy_, regions * occupancy_bytes, "occupancy layer"},
          std::tuple{&mean_, std::max<std::size_t>(regions * mean_bytes, 8), "voxel-mean layer"},
          std::tuple{&outputs_[0], cells * 4, "elevation"},
          std::tuple{&outputs_[1], cells * 4, "clearance"},
          std::tuple{&outputs_[2], cells * 4, "kind"},
          std::tuple{&outputs_[3], cells * 4, "observed count"},
          std::tuple{&outputs_[4], cells * 4, "reference"}}) {
      if (auto ok = reserve(*buffer, bytes, what); !ok) {
        return ok;
      }
    }

    cudaStream_t s = stream_.get();
    cudaError_t status = cudaMemcpyAsync(table_.memory.get(), plan.region_table.data(),
                                         plan.region_table.size() * 4, cudaMemcpyHostToDevice, s);
    if (status == cudaSuccess) {
      status = cudaMemcpyAsync(region_slots_.memory.get(), identity_.data(), regions * 4,
                               cudaMemcpyHostToDevice, s);
    }
    for (std::size_t c = 0; c < slots.size() && status == cudaSuccess; ++c) {
      status = cudaMemcpyAsync(occupancy_.as<std::byte>() + c * occupancy_bytes,
                               store.layerBytes(slots[c], occupancy_layer), occupancy_bytes,
                               cudaMemcpyHostToDevice, s);
      if (with_mean && status == cudaSuccess) {
        status = cudaMemcpyAsync(mean_.as<std::byte>() + c * mean_bytes,
                                 store.layerBytes(slots[c], mean_layer), mean_bytes,
                                 cudaMemcpyHostToDevice, s);
      }
    }
    if (status != cudaSuccess) {
      return Unexpected(cuda::cudaFailure("CUDA height map: uploading the map regions", status));
    }
    cuda::HeightmapKernelBuffers buffers;
    buffers.table = table_.as<const std::uint32_t>();
    buffers.region_slots = region_slots_.as<const std::uint32_t>();
    buffers.occupancy = occupancy_.as<const float>();
    buffers.masks = masks_.as<rm_hm_mask>();
    buffers.mean = mean_.as<const rm_voxel_mean>();
    buffers.elevation = outputs_[0].as<float>();
    buffers.clearance = outputs_[1].as<float>();
    buffers.kind = outputs_[2].as<std::uint32_t>();
    buffers.samples = outputs_[3].as<std::uint32_t>();
    buffers.reference = outputs_[4].as<float>();
    const rm_heightmap_params& p = plan.params;
    status = cuda::launchHeightmapMasks(s, block_threads_, buffers, p,
                                        static_cast<std::uint32_t>(slots.size()));
    if (status == cudaSuccess && (p.flags & RM_HM_FLAG_FILL) != 0) {
      const rm_i32 rings = rm_hm_ring_count(p);
      for (rm_i32 k = 0; k < rings && status == cudaSuccess; ++k) {
        status = cuda::launchHeightmapFillRing(s, block_threads_, buffers, p, k);
      }
    } else if (status == cudaSuccess) {
      status = cuda::launchHeightmapPlanar(s, block_threads_, buffers, p);
    }
    if (status != cudaSuccess) {
      return Unexpected(cuda::cudaFailure("CUDA height map: launching the kernel", status));
    }
    void* targets[kOutputs] = {out.elevation.data(), out.clearance.data(), out.kind.data(),
                               out.observed_count.data(), out.reference.data()};
    for (std::size_t l = 0; l < kOutputs && status == cudaSuccess; ++l) {
      status = cudaMemcpyAsync(targets[l], outputs_[l].memory.get(), cells * 4,
                               cudaMemcpyDeviceToHost, s);
    }
    if (status == cudaSuccess) {
      status = cudaStreamSynchronize(s);
    }
    if (status != cudaSuccess) {
      return Unexpected(cuda::cudaFailure("CUDA height map: reading the layers back", status));
    }
    return {};
  }

 private:
  static constexpr std::size_t kOutputs = 5;  // elevation, clearance, kind, samples, reference

  Expected<void, Error> reserve(GrowingBuffer& buffer, std::size_t bytes, const char* what) {
    bytes = std::max<std::size_t>(bytes, 4);
    if (buffer.memory && buffer.bytes >= bytes) {
      return {};
    }
    (void)cudaStreamSynchronize(stream_.get());
    buffer.memory.reset();
    buffer.bytes = 0;
    auto memory = cuda::allocateDevice(bytes, std::string("CUDA height map: ") + what);
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
  GrowingBuffer table_;
  GrowingBuffer region_slots_;
  GrowingBuffer masks_;
  GrowingBuffer occupancy_;
  GrowingBuffer mean_;
  GrowingBuffer outputs_[kOutputs];
  std::vector<std::uint32_t> identity_;
};

}  // namespace

Result<std::unique_ptr<heightmap::HeightmapGenerator>> createCudaHeightmapGenerator(
    const CudaHeightmapOptions& options) {
  if (options.block_threads == 0 || options.block_threads > 1024 ||
      options.block_threads % 32 != 0) {
    return fail(ErrorCode::kInvalidArgument,
                "CUDA block size must be a multiple of 32 from 32 to 1024 threads");
  }
  auto devices = cuda::listDevices();
  if (!devices) {
    return Unexpected(devices.error());
  }
  auto device = cuda::selectDevice(*devices, options.device);
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
