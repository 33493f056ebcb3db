// SPDX-License-Identifier: BSD-3-Clause
// Backend creation for the command line.
#include "tools/raymap/backend_choice.hpp"

#include <vector>

#include "src/map/cpu_backend.hpp"
#if defined(RAYMAP_HAVE_OPENCL)
#include "src/opencl/opencl_backend.hpp"
#endif

namespace raymap::cli {
namespace {

Result<std::unique_ptr<Backend>> createCpu(VoxelMap& map, const BackendChoice& choice) {
  CpuBackendOptions options;
  options.threads = choice.threads;
  return createCpuBackend(map, options);
}

Result<std::unique_ptr<Backend>> createDevice(VoxelMap& map, const BackendChoice& choice) {
#if defined(RAYMAP_HAVE_OPENCL)
  if (choice.name == "opencl") {
    OpenClBackendOptions options;
    options.device.platform = choice.opencl_platform;
    options.device.device = choice.opencl_device;
    options.cache_bytes = choice.gpu_cache_bytes;
    options.cache_regions = choice.gpu_cache_regions;
    options.memory = choice.gpu_memory == "cache"    ? DeviceMemory::kCache
                     : choice.gpu_memory == "shared" ? DeviceMemory::kShared
                                                     : DeviceMemory::kAuto;
    options.batch_rays = choice.gpu_batch_rays;
    auto backend = createOpenClBackend(map, options);
    if (!backend) {
      return fail(backend.error().code, "--backend opencl: " + backend.error().message);
    }
    return backend;
  }
#else
  (void)map;
  if (choice.name == "opencl") {
    return fail(ErrorCode::kUnsupported,
                "--backend opencl: this build has no OpenCL backend (install ocl-icd-opencl-dev "
                "and opencl-headers, then build again)");
  }
#endif
  return fail(ErrorCode::kInvalidArgument, "--backend: unknown backend '" + choice.name + "'");
}

}  // namespace

std::vector<std::string> availableBackends() {
#if defined(RAYMAP_HAVE_OPENCL)
  return {"cpu", "opencl"};
#else
  return {"cpu"};
#endif
}

Result<CreatedBackend> createBackend(VoxelMap& map, const BackendChoice& choice) {
  CreatedBackend created;
  if (choice.name == "cpu") {
    auto cpu = createCpu(map, choice);
    if (!cpu) {
      return Unexpected(cpu.error());
    }
    created.backend = std::move(*cpu);
    return created;
  }
  auto device = createDevice(map, choice);
  if (device) {
    created.backend = std::move(*device);
    created.startup_warning = created.backend->startupWarning();
    return created;
  }
  if (!choice.fallback_cpu) {
    return Unexpected(Error{device.error().code,
                            device.error().message + " (--fallback cpu maps on the CPU instead)"});
  }
  auto cpu = createCpu(map, choice);
  if (!cpu) {
    return Unexpected(cpu.error());
  }
  created.backend = std::move(*cpu);
  created.fallback_warning = device.error().message + "; falling back to the CPU backend";
  return created;
}

}  // namespace raymap::cli
