// SPDX-License-Identifier: BSD-3-Clause
#include "src/device/opencl/opencl_heightmap.hpp"

#include <algorithm>
#include <initializer_list>
#include <string>
#include <utility>
#include <vector>

#include "kernels/common/heightmap.h"
#include "src/device/opencl/opencl_backend.hpp"
#include "src/device/staging/resident_read.hpp"
#include "src/heightmap/device_upload.hpp"

namespace raymap {
namespace kernels {
extern const char* const kHeightmapSource;  // embedded at build time
}  // namespace kernels

namespace {

constexpr std::size_t kWorkGroup = 64;
/// rm_heightmap_fill_ring's `ring`: after the parameter block and its 13 buffers.
constexpr cl_uint kFillRingArgument = 14;

class OpenClHeightmapGenerator final : public heightmap::HeightmapGenerator {
 public:
  /// Standalone: its own context, reading the host store.
  explicit OpenClHeightmapGenerator(opencl::DeviceContext ctx)
      : owned_ctx_(std::move(ctx)), ctx_(&owned_ctx_) {
    setLocalSize();
  }
  /// In `backend`'s context, reading the layers where it left them.
  explicit OpenClHeightmapGenerator(opencl::BackendDevice& backend)
      : ctx_(&backend.context()), backend_(&backend) {
    setLocalSize();
  }
  ~OpenClHeightmapGenerator() override {
    // The backend's queue is the backend's to drain (generate() returns with it idle anyway).
    if (owned_ctx_.queue) {
      (void)clFinish(owned_ctx_.queue.get());
    }
  }

  Expected<void, Error> initialise(const opencl::ProgramCacheOptions& program_cache) {
    auto program =
        opencl::buildProgram(*ctx_, kernels::kHeightmapSource, "-cl-std=CL1.2", program_cache);
    if (!program) {
      return Unexpected(program.error());
    }
    program_ = std::move(program->program);
    return opencl::createKernels(program_, {{&masks_kernel_, "rm_heightmap_masks"},
                                            {&planar_, "rm_heightmap_planar"},
                                            {&fill_, "rm_heightmap_fill_ring"}});
  }

  const char* name() const noexcept override { return "opencl"; }
  std::uint64_t bytesCopied() const noexcept override { return upload_.total_bytes; }
  std::uint64_t mapBytesCopied() const noexcept override { return upload_.total_map_bytes; }
  bool readsHostStore() const noexcept override { return backend_ == nullptr; }
  std::string deviceName() const override {
    return ctx_->info.device_name + " (" + ctx_->info.platform_name + ")";
  }

  Expected<void, Error> generate(const VoxelMap& map, const heightmap::HeightmapPlan& plan,
                                 heightmap::HeightMap& out) override {
    heightmap::prepareOutput(plan, out);
    if (auto ok = uploadRegions(map, plan); !ok) {
      return ok;
    }
    if (auto ok = launchKernels(plan, out); !ok) {
      return ok;
    }
    if (auto ok = readBack(out); !ok) {
      return ok;
    }
    upload_.countGeneration(plan, out);
    return {};
  }

 private:
  /// The plan's regions where the kernels read them: the backend's resident layers, or copies
  /// of the host store's regions in this generator's buffers.
  Expected<void, Error> uploadRegions(const VoxelMap& map, const heightmap::HeightmapPlan& plan) {
    using namespace heightmap;
    auto slots = resident_.prepare(backend_ == nullptr ? nullptr : &backend_->staged(), map,
                                   plan.region_slots, "OpenCL");
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
    cl_int status = CL_SUCCESS;
    upload_.forEachCopy(
        map, plan,
        [&](DeviceBuffer buffer, std::size_t offset, const void* data, std::size_t bytes) {
          if (status == CL_SUCCESS) {
            status = clEnqueueWriteBuffer(ctx_->queue.get(), buffers_[buffer].handle.get(),
                                          CL_FALSE, offset, bytes, data, 0, nullptr, nullptr);
          }
        });
    if (status != CL_SUCCESS) {
      return deviceError("uploading the map regions", status);
    }
    return {};
  }

  /// The occupancy masks, then the column search (planar, or ring by ring when filling).
  Expected<void, Error> launchKernels(const heightmap::HeightmapPlan& plan,
                                      const heightmap::HeightMap& out) {
    using namespace heightmap;
    cl_int status = CL_SUCCESS;
    const rm_heightmap_params& p = plan.params;
    const auto region_count = static_cast<cl_uint>(plan.region_slots.size());
    if (auto ok = setArguments(masks_kernel_.get(), p,
                               {kRegionSlotsBuffer, kOccupancyBuffer, kMasksBuffer}, &region_count);
        !ok) {
      return ok;
    }
    const auto plane =
        static_cast<std::size_t>(p.region_voxels) * static_cast<std::size_t>(p.region_voxels);
    if (region_count > 0) {
      status = launch(masks_kernel_.get(), region_count * plane);
    }
    const bool fill = (p.flags & RM_HM_FLAG_FILL) != 0;
    cl_kernel search = fill ? fill_.get() : planar_.get();
    if (auto ok =
            setArguments(search, p,
                         {kTableBuffer, kRegionSlotsBuffer, kMasksBuffer, kMeanBuffer, kNdtBuffer,
                          kElevationBuffer, kClearanceBuffer, kKindBuffer, kObservedCountBuffer,
                          kReferenceBuffer, kNormalXBuffer, kNormalYBuffer, kNormalZBuffer},
                         nullptr);
        !ok) {
      return ok;
    }
    if (fill) {
      const rm_i32 rings = rm_hm_ring_count(p);
      for (rm_i32 k = 0; k < rings && status == CL_SUCCESS; ++k) {
        status = clSetKernelArg(search, kFillRingArgument, sizeof k, &k);
        if (status == CL_SUCCESS) {
          status = launch(search, rm_hm_ring_size(k));
        }
      }
    } else if (status == CL_SUCCESS) {
      status = launch(search, out.cellCount());
    }
    if (status != CL_SUCCESS) {
      return deviceError("launching the height-map kernels", status);
    }
    return {};
  }

  /// The output layers copied back; returns once the queue is idle.
  Expected<void, Error> readBack(heightmap::HeightMap& out) {
    using namespace heightmap;
    cl_command_queue q = ctx_->queue.get();
    cl_int status = CL_SUCCESS;
    DeviceUpload::forEachOutput(out, [&](DeviceBuffer buffer, void* target) {
      if (status == CL_SUCCESS) {
        status = clEnqueueReadBuffer(q, buffers_[buffer].handle.get(), CL_FALSE, 0,
                                     out.cellCount() * 4, target, 0, nullptr, nullptr);
      }
    });
    if (status == CL_SUCCESS) {
      status = clFinish(q);
    }
    if (status != CL_SUCCESS) {
      return deviceError("reading the height map back", status);
    }
    return {};
  }

  /// A device buffer that grows on demand (never shrinks).
  struct GrowingBuffer {
    opencl::BufferHandle handle;
    std::size_t bytes = 0;
  };

  Expected<void, Error> reserve(GrowingBuffer& buffer, std::size_t bytes,
                                heightmap::DeviceBuffer what) {
    if (buffer.handle && buffer.bytes >= bytes) {
      return {};
    }
    (void)clFinish(ctx_->queue.get());
    buffer.handle.reset();
    buffer.bytes = 0;
    auto created =
        opencl::createBuffer(*ctx_, bytes, std::string("height map: ") + heightmap::toString(what));
    if (!created) {
      return Unexpected(created.error());
    }
    buffer.handle = std::move(*created);
    buffer.bytes = bytes;
    return {};
  }

  /// Argument 0 is the parameter block, then the buffers in order, then `last` if given.
  Expected<void, Error> setArguments(cl_kernel kernel, const rm_heightmap_params& p,
                                     std::initializer_list<heightmap::DeviceBuffer> buffers,
                                     const cl_uint* last) {
    cl_int status = clSetKernelArg(kernel, 0, sizeof p, &p);
    cl_uint index = 1;
    for (const heightmap::DeviceBuffer buffer : buffers) {
      if (status == CL_SUCCESS) {
        const cl_mem mem = bufferFor(buffer);
        status = clSetKernelArg(kernel, index, sizeof(cl_mem), &mem);
      }
      ++index;
    }
    if (last != nullptr && status == CL_SUCCESS) {
      status = clSetKernelArg(kernel, index, sizeof *last, last);
    }
    if (status != CL_SUCCESS) {
      return deviceError("setting the kernel arguments", status);
    }
    return {};
  }

  /// The buffer a kernel argument binds: the map's layers are the backend's where resident.
  cl_mem bufferFor(heightmap::DeviceBuffer buffer) const noexcept {
    if (upload_.resident && heightmap::DeviceUpload::isMapLayer(buffer)) {
      return backend_->layerBuffer(upload_.layerOf(buffer, backend_->staged().integratedMap()));
    }
    return buffers_[buffer].handle.get();
  }

  void setLocalSize() {
    local_size_ = std::min(kWorkGroup, std::max<std::size_t>(ctx_->info.max_work_group_size, 1));
  }

  cl_int launch(cl_kernel kernel, std::size_t items) {
    const std::size_t global = (items + local_size_ - 1) / local_size_ * local_size_;
    return clEnqueueNDRangeKernel(ctx_->queue.get(), kernel, 1, nullptr, &global, &local_size_, 0,
                                  nullptr, nullptr);
  }

  Unexpected<Error> deviceError(const char* what, cl_int status) const {
    return fail(ErrorCode::kUnsupported, std::string("OpenCL height map: ") + what + ": " +
                                             opencl::errorName(status) + " on " +
                                             ctx_->info.device_name);
  }

  opencl::DeviceContext owned_ctx_;  // standalone only; first member with handles: released last
  const opencl::DeviceContext* ctx_;
  opencl::BackendDevice* backend_ = nullptr;  // in the backend's context: it outlives this
  opencl::ProgramHandle program_;
  opencl::KernelHandle masks_kernel_;
  opencl::KernelHandle planar_;
  opencl::KernelHandle fill_;
  std::size_t local_size_ = kWorkGroup;
  GrowingBuffer buffers_[heightmap::kDeviceBufferCount];
  heightmap::DeviceUpload upload_;
  gpu::ResidentRead resident_;
};

}  // namespace

Result<std::unique_ptr<heightmap::HeightmapGenerator>> createOpenClHeightmapGenerator(
    const OpenClHeightmapOptions& options) {
  auto device = opencl::findDevice(options.device);
  if (!device) {
    return Unexpected(device.error());
  }
  auto ctx = opencl::createContext(*device);
  if (!ctx) {
    return Unexpected(ctx.error());
  }
  auto generator = std::make_unique<OpenClHeightmapGenerator>(std::move(*ctx));
  if (auto ok = generator->initialise(options.program_cache); !ok) {
    return Unexpected(ok.error());
  }
  return std::unique_ptr<heightmap::HeightmapGenerator>(std::move(generator));
}

Result<std::unique_ptr<heightmap::HeightmapGenerator>> createOpenClHeightmapGenerator(
    Backend& backend, const opencl::ProgramCacheOptions& program_cache) {
  opencl::BackendDevice* device = opencl::backendDevice(backend);
  if (device == nullptr) {
    return fail(ErrorCode::kInvalidArgument, std::string("an OpenCL height-map generator cannot "
                                                         "share the context of the ") +
                                                 backend.name() + " backend");
  }
  auto generator = std::make_unique<OpenClHeightmapGenerator>(*device);
  if (auto ok = generator->initialise(program_cache); !ok) {
    return Unexpected(ok.error());
  }
  return std::unique_ptr<heightmap::HeightmapGenerator>(std::move(generator));
}

}  // namespace raymap
