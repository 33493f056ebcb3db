// SPDX-License-Identifier: BSD-3-Clause
// Backend creation for the command line and the service.
#include "src/device/backend_choice.hpp"

#include <vector>

#include "src/device/staging/device_planner.hpp"
#include "src/map/cpu_backend.hpp"
#if defined(RAYMAP_HAVE_OPENCL)
#include "src/device/opencl/opencl_backend.hpp"
#include "src/device/opencl/opencl_heightmap.hpp"
#endif
#if defined(RAYMAP_HAVE_CUDA)
#include "src/device/cuda/cuda_backend.hpp"
#include "src/device/cuda/cuda_heightmap.hpp"
#endif

namespace raymap::backends {
namespace {

Result<std::unique_ptr<Backend>> createCpu(VoxelMap& map, const BackendChoice& choice) {
  CpuBackendOptions options;
  options.threads = choice.threads;
  return createCpuBackend(map, options);
}

#if defined(RAYMAP_HAVE_OPENCL) || defined(RAYMAP_HAVE_CUDA)
/// The options every device backend shares.
void setDeviceOptions(const BackendChoice& choice, DeviceBackendOptions* options) {
  options->cache_bytes = choice.gpu_cache_bytes;
  options->cache_regions = choice.gpu_cache_regions;
  options->memory = choice.gpu_memory == "cache"    ? DeviceMemory::kCache
                    : choice.gpu_memory == "shared" ? DeviceMemory::kShared
                                                    : DeviceMemory::kAuto;
  options->batch_rays = choice.gpu_batch_rays;
  options->planning = gpu::planningNamed(choice.device_planning).value_or(gpu::Planning::kHost);
}

/// The backend's creation, with its errors prefixed by the option that chose it.
Result<std::unique_ptr<Backend>> named(Result<std::unique_ptr<Backend>> backend,
                                       const std::string& name) {
  if (!backend) {
    return fail(backend.error().code, "backend.name: " + name + ": " + backend.error().message);
  }
  return backend;
}
#endif

/// Why backend.name: NAME cannot work in this build (the API was not found at configure time).
[[maybe_unused]] Unexpected<Error> notBuilt(const std::string& name) {
  if (name == "opencl") {
    return fail(
        ErrorCode::kUnsupported,
        "backend.name: opencl: this build has no OpenCL backend (install ocl-icd-opencl-dev "
        "and opencl-headers, then build again)");
  }
  if (name == "cuda") {
    return fail(
        ErrorCode::kUnsupported,
        "backend.name: cuda: this build has no CUDA backend (it is built whenever CMake finds "
        "nvcc; install the CUDA toolkit, then configure again)");
  }
  return fail(ErrorCode::kInvalidArgument, "backend.name: unknown backend '" + name + "'");
}

Result<std::unique_ptr<Backend>> createDevice(VoxelMap& map, const BackendChoice& choice) {
  (void)map;
  if (choice.name == "opencl") {
#if defined(RAYMAP_HAVE_OPENCL)
    OpenClBackendOptions options;
    setDeviceOptions(choice, &options);
    options.device.platform = choice.opencl_platform;
    options.device.device = choice.opencl_device;
    options.span_work = spanWorkNamed(choice.opencl_span_work).value_or(SpanWork::kAuto);
    return named(createOpenClBackend(map, options), choice.name);
#else
    return notBuilt(choice.name);
#endif
  }
  if (choice.name == "cuda") {
#if defined(RAYMAP_HAVE_CUDA)
    CudaBackendOptions options;
    setDeviceOptions(choice, &options);
    options.device = choice.cuda_device;
    return named(createCudaBackend(map, options), choice.name);
#else
    return notBuilt(choice.name);
#endif
  }
  return notBuilt(choice.name);
}

/// The device height-map generator of backend.name: NAME.
Result<std::unique_ptr<heightmap::HeightmapGenerator>> createDeviceHeightmap(
    const BackendChoice& choice) {
  if (choice.name == "opencl") {
#if defined(RAYMAP_HAVE_OPENCL)
    OpenClHeightmapOptions options;
    options.device.platform = choice.opencl_platform;
    options.device.device = choice.opencl_device;
    auto generator = createOpenClHeightmapGenerator(options);
    if (!generator) {
      return fail(generator.error().code, "backend.name: opencl: " + generator.error().message);
    }
    return generator;
#else
    return notBuilt(choice.name);
#endif
  }
  if (choice.name == "cuda") {
#if defined(RAYMAP_HAVE_CUDA)
    CudaHeightmapOptions options;
    options.device = choice.cuda_device;
    auto generator = createCudaHeightmapGenerator(options);
    if (!generator) {
      return fail(generator.error().code, "backend.name: cuda: " + generator.error().message);
    }
    return generator;
#else
    return notBuilt(choice.name);
#endif
  }
  return notBuilt(choice.name);
}

}  // namespace

std::vector<std::string> availableBackends() {
  std::vector<std::string> names{"cpu"};
#if defined(RAYMAP_HAVE_OPENCL)
  names.emplace_back("opencl");
#endif
#if defined(RAYMAP_HAVE_CUDA)
  names.emplace_back("cuda");
#endif
  return names;
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
  if (!gpu::planningNamed(choice.device_planning)) {
    return fail(ErrorCode::kInvalidArgument,
                "device planning '" + choice.device_planning + "': must be host or device");
  }
  auto device = createDevice(map, choice);
  if (device) {
    created.backend = std::move(*device);
    created.startup_warning = created.backend->startupWarning();
    return created;
  }
  if (!choice.fallback_cpu) {
    return Unexpected(
        Error{device.error().code,
              device.error().message + " (backend.fallback: cpu maps on the CPU instead)"});
  }
  auto cpu = createCpu(map, choice);
  if (!cpu) {
    return Unexpected(cpu.error());
  }
  created.backend = std::move(*cpu);
  created.fallback_warning = device.error().message + "; falling back to the CPU backend";
  return created;
}

}  // namespace raymap::backends

namespace raymap::backends {

Result<CreatedHeightmapGenerator> createHeightmapGenerator(const BackendChoice& choice) {
  CreatedHeightmapGenerator created;
  if (choice.name == "cpu") {
    created.generator = heightmap::makeCpuHeightmapGenerator();
    return created;
  }
  auto device = createDeviceHeightmap(choice);
  if (device) {
    created.generator = std::move(*device);
    return created;
  }
  if (!choice.fallback_cpu) {
    return Unexpected(
        Error{device.error().code,
              device.error().message + " (backend.fallback: cpu generates on the CPU)"});
  }
  created.generator = heightmap::makeCpuHeightmapGenerator();
  created.fallback_warning = device.error().message + "; falling back to the CPU";
  return created;
}

Result<CreatedHeightmapGenerator> createHeightmapGenerator(Backend& backend) {
  CreatedHeightmapGenerator created;
  const std::string name = backend.name();
  if (name == "cpu") {
    created.generator = heightmap::makeCpuHeightmapGenerator();
    return created;
  }
  Result<std::unique_ptr<heightmap::HeightmapGenerator>> device = notBuilt(name);
#if defined(RAYMAP_HAVE_OPENCL)
  if (name == "opencl") {
    device = createOpenClHeightmapGenerator(backend, {});
  }
#endif
#if defined(RAYMAP_HAVE_CUDA)
  if (name == "cuda") {
    device = createCudaHeightmapGenerator(backend);
  }
#endif
  if (!device) {
    return fail(device.error().code, "backend.name: " + name + ": " + device.error().message);
  }
  created.generator = std::move(*device);
  return created;
}

}  // namespace raymap::backends
