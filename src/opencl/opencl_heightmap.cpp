// SPDX-License-Identifier: BSD-3-Clause
#include "src/opencl/opencl_heightmap.hpp"

#include <algorithm>
#include <initializer_list>
#include <string>
#include <tuple>
#include <vector>

#include "kernels/common/heightmap.h"

namespace raymap {
namespace kernels {
extern const char* const kHeightmapSource;  // embedded at build time
}  // namespace kernels

namespace {

constexpr std::size_t kWorkGroup = 64;

class OpenClHeightmapGenerator final : public heightmap::HeightmapGenerator {
 public:
  explicit OpenClHeightmapGenerator(opencl::DeviceContext ctx) : ctx_(std::move(ctx)) {
    local_size_ = std::min(kWorkGroup, std::max<std::size_t>(ctx_.info.max_work_group_size, 1));
  }
  ~OpenClHeightmapGenerator() override {
    if (ctx_.queue) {
      (void)clFinish(ctx_.queue.get());
    }
  }

  Expected<void, Error> initialise(const OpenClHeightmapOptions& options) {
    auto program = opencl::buildProgram(ctx_, kernels::kHeightmapSource, "-cl-std=CL1.2",
                                        options.program_cache);
    if (!program) {
      return Unexpected(program.error());
    }
    program_ = std::move(program->program);
    for (auto [handle, name] : {std::pair{&masks_kernel_, "rm_heightmap_masks"},
                                std::pair{&planar_, "rm_heightmap_planar"},
                                std::pair{&fill_, "rm_heightmap_fill_ring"}}) {
      auto kernel = opencl::createKernel(program_, name);
      if (!kernel) {
        return Unexpected(kernel.error());
      }
      *handle = std::move(*kernel);
    }
    return {};
  }

  const char* name() const noexcept override { return "opencl"; }
  std::string deviceName() const override {
    return ctx_.info.device_name + " (" + ctx_.info.platform_name + ")";
  }

  Expected<void, Error> generate(const VoxelMap& map, const heightmap::HeightmapPlan& plan,
                                 heightmap::HeightMap& out) override {
    heightmap::prepareOutput(plan, out);
    const RegionStore& store = map.store();
    const int occupancy_layer = map.occupancyLayer();
    const int mean_layer = map.meanLayer();
    const rm_heightmap_params& p = plan.params;
    const bool with_mean = (p.flags & RM_HM_FLAG_MEAN) != 0 && mean_layer >= 0;

    // Regions are uploaded in the plan's region order, so region r sits in slot r on the device.
    const std::vector<std::uint32_t>& slots = plan.region_slots;
    identity_.resize(std::max<std::size_t>(slots.size(), 1));
    for (std::size_t r = 0; r < identity_.size(); ++r) {
      identity_[r] = static_cast<std::uint32_t>(r);
    }
    const std::size_t regions = identity_.size();
    const auto plane =
        static_cast<std::size_t>(p.region_voxels) * static_cast<std::size_t>(p.region_voxels);
    const std::size_t mask_bytes = regions * plane *
                                   static_cast<std::size_t>(rm_hm_mask_words(p.region_voxels)) *
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

    cl_command_queue q = ctx_.queue.get();
    cl_int status = CL_SUCCESS;
    auto write = [&](const GrowingBuffer& buffer, std::size_t offset, const void* data,
                     std::size_t bytes) {
      if (status == CL_SUCCESS && bytes > 0) {
        status = clEnqueueWriteBuffer(q, buffer.handle.get(), CL_FALSE, offset, bytes, data, 0,
                                      nullptr, nullptr);
      }
    };
    write(table_, 0, plan.region_table.data(), plan.region_table.size() * 4);
    write(region_slots_, 0, identity_.data(), regions * 4);
    for (std::size_t c = 0; c < slots.size(); ++c) {
      write(occupancy_, c * occupancy_bytes, store.layerBytes(slots[c], occupancy_layer),
            occupancy_bytes);
      if (with_mean) {
        write(mean_, c * mean_bytes, store.layerBytes(slots[c], mean_layer), mean_bytes);
      }
    }
    if (status != CL_SUCCESS) {
      return deviceError("uploading the map regions", status);
    }

    const auto region_count = static_cast<cl_uint>(slots.size());
    if (auto ok = setArguments(masks_kernel_.get(), p, {&region_slots_, &occupancy_, &masks_},
                               &region_count);
        !ok) {
      return ok;
    }
    if (region_count > 0) {
      status = launch(masks_kernel_.get(), region_count * plane);
    }
    const bool fill = (p.flags & RM_HM_FLAG_FILL) != 0;
    cl_kernel search = fill ? fill_.get() : planar_.get();
    if (auto ok = setArguments(search, p,
                               {&table_, &region_slots_, &masks_, &mean_, &outputs_[0],
                                &outputs_[1], &outputs_[2], &outputs_[3], &outputs_[4]},
                               nullptr);
        !ok) {
      return ok;
    }
    if (fill) {
      const rm_i32 rings = rm_hm_ring_count(p);
      for (rm_i32 k = 0; k < rings && status == CL_SUCCESS; ++k) {
        status = clSetKernelArg(search, 10, sizeof k, &k);
        if (status == CL_SUCCESS) {
          status = launch(search, rm_hm_ring_size(k));
        }
      }
    } else if (status == CL_SUCCESS) {
      status = launch(search, cells);
    }
    if (status != CL_SUCCESS) {
      return deviceError("launching the height-map kernels", status);
    }
    void* targets[kOutputs] = {out.elevation.data(), out.clearance.data(), out.kind.data(),
                               out.observed_count.data(), out.reference.data()};
    for (std::size_t l = 0; l < kOutputs && status == CL_SUCCESS; ++l) {
      status = clEnqueueReadBuffer(q, outputs_[l].handle.get(), CL_FALSE, 0, cells * 4, targets[l],
                                   0, nullptr, nullptr);
    }
    if (status == CL_SUCCESS) {
      status = clFinish(q);
    }
    if (status != CL_SUCCESS) {
      return deviceError("reading the height map back", status);
    }
    return {};
  }

 private:
  static constexpr std::size_t kOutputs = 5;  // elevation, clearance, kind, samples, reference

  /// A device buffer that grows on demand (never shrinks).
  struct GrowingBuffer {
    opencl::BufferHandle handle;
    std::size_t bytes = 0;
  };

  Expected<void, Error> reserve(GrowingBuffer& buffer, std::size_t bytes, const char* what) {
    bytes = std::max<std::size_t>(bytes, 4);
    if (buffer.handle && buffer.bytes >= bytes) {
      return {};
    }
    (void)clFinish(ctx_.queue.get());
    buffer.handle.reset();
    buffer.bytes = 0;
    auto created = opencl::createBuffer(ctx_, bytes, std::string("height map: ") + what);
    if (!created) {
      return Unexpected(created.error());
    }
    buffer.handle = std::move(*created);
    buffer.bytes = bytes;
    return {};
  }

  /// Argument 0 is the parameter block, then the buffers in order, then `last` if given.
  Expected<void, Error> setArguments(cl_kernel kernel, const rm_heightmap_params& p,
                                     std::initializer_list<const GrowingBuffer*> buffers,
                                     const cl_uint* last) {
    cl_int status = clSetKernelArg(kernel, 0, sizeof p, &p);
    cl_uint index = 1;
    for (const GrowingBuffer* buffer : buffers) {
      if (status == CL_SUCCESS) {
        const cl_mem mem = buffer->handle.get();
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

  cl_int launch(cl_kernel kernel, std::size_t items) {
    const std::size_t global = (items + local_size_ - 1) / local_size_ * local_size_;
    return clEnqueueNDRangeKernel(ctx_.queue.get(), kernel, 1, nullptr, &global, &local_size_, 0,
                                  nullptr, nullptr);
  }

  Unexpected<Error> deviceError(const char* what, cl_int status) const {
    return fail(ErrorCode::kUnsupported, std::string("OpenCL height map: ") + what + ": " +
                                             opencl::errorName(status) + " on " +
                                             ctx_.info.device_name);
  }

  opencl::DeviceContext ctx_;
  opencl::ProgramHandle program_;
  opencl::KernelHandle masks_kernel_;
  opencl::KernelHandle planar_;
  opencl::KernelHandle fill_;
  std::size_t local_size_ = kWorkGroup;
  GrowingBuffer table_;
  GrowingBuffer region_slots_;
  GrowingBuffer masks_;
  GrowingBuffer occupancy_;
  GrowingBuffer mean_;
  GrowingBuffer outputs_[kOutputs];
  std::vector<std::uint32_t> identity_;
};

}  // namespace

Result<std::unique_ptr<heightmap::HeightmapGenerator>> createOpenClHeightmapGenerator(
    const OpenClHeightmapOptions& options) {
  auto devices = opencl::listDevices();
  if (!devices) {
    return Unexpected(devices.error());
  }
  auto device = opencl::selectDevice(*devices, options.device);
  if (!device) {
    return Unexpected(device.error());
  }
  auto ctx = opencl::createContext(*device);
  if (!ctx) {
    return Unexpected(ctx.error());
  }
  auto generator = std::make_unique<OpenClHeightmapGenerator>(std::move(*ctx));
  if (auto ok = generator->initialise(options); !ok) {
    return Unexpected(ok.error());
  }
  return std::unique_ptr<heightmap::HeightmapGenerator>(std::move(generator));
}

}  // namespace raymap
