// SPDX-License-Identifier: BSD-3-Clause
#include "src/opencl/opencl_heightmap.hpp"

#include <algorithm>
#include <string>
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
    for (auto [handle, name] : {std::pair{&planar_, "rm_heightmap_planar"},
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
    const bool with_mean = (plan.params.flags & RM_HM_FLAG_MEAN) != 0 && mean_layer >= 0;

    // Regions under the box, packed: the table names compact indices into the uploaded layers.
    compact_table_.assign(plan.region_table.begin(), plan.region_table.end());
    slots_.clear();
    for (std::uint32_t& entry : compact_table_) {
      if (entry != RM_HM_NO_REGION) {
        slots_.push_back(entry);
        entry = static_cast<std::uint32_t>(slots_.size() - 1);
      }
    }
    const std::size_t regions = std::max<std::size_t>(slots_.size(), 1);
    const std::size_t occupancy_bytes = store.layerRegionBytes(occupancy_layer);
    const std::size_t mean_bytes = with_mean ? store.layerRegionBytes(mean_layer) : 0;
    const std::size_t cells = out.cellCount();
    if (auto ok = reserve(table_, table_bytes_, compact_table_.size() * 4, "region table"); !ok) {
      return ok;
    }
    if (auto ok =
            reserve(occupancy_, occupancy_bytes_, regions * occupancy_bytes, "occupancy layer");
        !ok) {
      return ok;
    }
    if (auto ok = reserve(mean_, mean_bytes_, std::max<std::size_t>(regions * mean_bytes, 8),
                          "voxel-mean layer");
        !ok) {
      return ok;
    }
    for (std::size_t l = 0; l < kOutputs; ++l) {
      if (auto ok = reserve(outputs_[l], output_bytes_[l], cells * 4, "height-map layer"); !ok) {
        return ok;
      }
    }

    cl_command_queue q = ctx_.queue.get();
    cl_int status = CL_SUCCESS;
    auto write = [&](const opencl::BufferHandle& buffer, std::size_t offset, const void* data,
                     std::size_t bytes) {
      if (status == CL_SUCCESS && bytes > 0) {
        status = clEnqueueWriteBuffer(q, buffer.get(), CL_FALSE, offset, bytes, data, 0, nullptr,
                                      nullptr);
      }
    };
    write(table_, 0, compact_table_.data(), compact_table_.size() * 4);
    for (std::size_t c = 0; c < slots_.size(); ++c) {
      write(occupancy_, c * occupancy_bytes, store.layerBytes(slots_[c], occupancy_layer),
            occupancy_bytes);
      if (with_mean) {
        write(mean_, c * mean_bytes, store.layerBytes(slots_[c], mean_layer), mean_bytes);
      }
    }
    if (status != CL_SUCCESS) {
      return deviceError("uploading the map regions", status);
    }

    const rm_heightmap_params& p = plan.params;
    cl_kernel kernel = (p.flags & RM_HM_FLAG_FILL) != 0 ? fill_.get() : planar_.get();
    cl_mem args[] = {table_.get(),      occupancy_.get(),  mean_.get(),       outputs_[0].get(),
                     outputs_[1].get(), outputs_[2].get(), outputs_[3].get(), outputs_[4].get()};
    status = clSetKernelArg(kernel, 0, sizeof p, &p);
    for (cl_uint a = 0; a < 8 && status == CL_SUCCESS; ++a) {
      status = clSetKernelArg(kernel, a + 1, sizeof(cl_mem), &args[a]);
    }
    if (status != CL_SUCCESS) {
      return deviceError("setting the kernel arguments", status);
    }
    auto launch = [&](std::size_t items) {
      const std::size_t global = (items + local_size_ - 1) / local_size_ * local_size_;
      status =
          clEnqueueNDRangeKernel(q, kernel, 1, nullptr, &global, &local_size_, 0, nullptr, nullptr);
    };
    if ((p.flags & RM_HM_FLAG_FILL) != 0) {
      const rm_i32 rings = rm_hm_ring_count(p);
      for (rm_i32 k = 0; k < rings && status == CL_SUCCESS; ++k) {
        status = clSetKernelArg(kernel, 9, sizeof k, &k);
        if (status == CL_SUCCESS) {
          launch(rm_hm_ring_size(k));
        }
      }
    } else {
      launch(cells);
    }
    if (status != CL_SUCCESS) {
      return deviceError("launching the height-map kernel", status);
    }
    void* targets[kOutputs] = {out.elevation.data(), out.clearance.data(), out.kind.data(),
                               out.observed_count.data(), out.reference.data()};
    for (std::size_t l = 0; l < kOutputs && status == CL_SUCCESS; ++l) {
      status = clEnqueueReadBuffer(q, outputs_[l].get(), CL_FALSE, 0, cells * 4, targets[l], 0,
                                   nullptr, nullptr);
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

  /// Grows `buffer` to at least `bytes` (never shrinks).
  Expected<void, Error> reserve(opencl::BufferHandle& buffer, std::size_t& capacity,
                                std::size_t bytes, const char* what) {
    bytes = std::max<std::size_t>(bytes, 4);
    if (buffer && capacity >= bytes) {
      return {};
    }
    (void)clFinish(ctx_.queue.get());
    buffer.reset();
    auto created = opencl::createBuffer(ctx_, bytes, std::string("height map: ") + what);
    if (!created) {
      capacity = 0;
      return Unexpected(created.error());
    }
    buffer = std::move(*created);
    capacity = bytes;
    return {};
  }

  Unexpected<Error> deviceError(const char* what, cl_int status) const {
    return fail(ErrorCode::kUnsupported, std::string("OpenCL height map: ") + what + ": " +
                                             opencl::errorName(status) + " on " +
                                             ctx_.info.device_name);
  }

  opencl::DeviceContext ctx_;
  opencl::ProgramHandle program_;
  opencl::KernelHandle planar_;
  opencl::KernelHandle fill_;
  std::size_t local_size_ = kWorkGroup;
  opencl::BufferHandle table_;
  opencl::BufferHandle occupancy_;
  opencl::BufferHandle mean_;
  opencl::BufferHandle outputs_[kOutputs];
  std::size_t table_bytes_ = 0;
  std::size_t occupancy_bytes_ = 0;
  std::size_t mean_bytes_ = 0;
  std::size_t output_bytes_[kOutputs] = {};
  std::vector<std::uint32_t> compact_table_;
  std::vector<std::uint32_t> slots_;
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
