// SPDX-License-Identifier: BSD-3-Clause
// CUDA device discovery through the runtime API.
#include "src/device/cuda/cuda_devices.hpp"

#include <cuda_runtime_api.h>

#include "src/device/cuda/cuda_handles.hpp"

namespace raymap::cuda {
namespace {

int attribute(cudaDeviceAttr attr, int device) {
  int value = 0;
  if (cudaDeviceGetAttribute(&value, attr, device) != cudaSuccess) {
    (void)cudaGetLastError();  // a later launch's check must not see this failure as its own
    return 0;
  }
  return value;
}

/// Why there is no usable device, in the user's terms.
Error noDevices(cudaError_t status, int runtime_version) {
  switch (status) {
    case cudaErrorInsufficientDriver:
      return Error{ErrorCode::kUnsupported,
                   "no CUDA driver: the NVIDIA driver is not installed or is older than CUDA " +
                       versionText(runtime_version) +
                       " needs (install or update the NVIDIA driver; on a Jetson, use the "
                       "JetPack build)"};
    case cudaErrorNoDevice:
      return Error{ErrorCode::kUnsupported,
                   "no CUDA device: the NVIDIA driver found none (check CUDA_VISIBLE_DEVICES "
                   "and that /dev/nvidia* or /dev/nvhost* are accessible)"};
    default:
      return cudaFailure("CUDA device discovery", status);
  }
}

}  // namespace

std::string versionText(int version) {
  return std::to_string(version / 1000) + "." + std::to_string((version % 1000) / 10);
}

Result<std::vector<DeviceInfo>> listDevices() {
  int runtime_version = 0;
  (void)cudaRuntimeGetVersion(&runtime_version);
  int count = 0;
  const cudaError_t status = cudaGetDeviceCount(&count);
  if (status != cudaSuccess || count <= 0) {
    // The failed call leaves a sticky "last error"; clear it so later calls start clean.
    (void)cudaGetLastError();
    return Unexpected(
        noDevices(status == cudaSuccess ? cudaErrorNoDevice : status, runtime_version));
  }
  int driver_version = 0;
  (void)cudaDriverGetVersion(&driver_version);
  std::vector<DeviceInfo> devices;
  for (int d = 0; d < count; ++d) {
    cudaDeviceProp prop{};
    if (const cudaError_t s = cudaGetDeviceProperties(&prop, d); s != cudaSuccess) {
      return Unexpected(cudaFailure("CUDA device " + std::to_string(d) + " properties", s));
    }
    DeviceInfo info;
    info.index = d;
    info.name = prop.name;
    info.compute_major = prop.major;
    info.compute_minor = prop.minor;
    info.multiprocessors = static_cast<std::uint32_t>(prop.multiProcessorCount);
    info.global_mem_bytes = prop.totalGlobalMem;
    info.integrated = attribute(cudaDevAttrIntegrated, d) != 0;
    info.can_map_host_memory = attribute(cudaDevAttrCanMapHostMemory, d) != 0;
    char bus[32] = {};
    if (!info.integrated && cudaDeviceGetPCIBusId(bus, sizeof(bus), d) == cudaSuccess) {
      info.pci_bus_id = bus;
    }
    info.runtime_version = runtime_version;
    info.driver_version = driver_version;
    devices.push_back(std::move(info));
  }
  return devices;
}

Result<DeviceInfo> findDevice(int index) {
  auto devices = listDevices();
  if (!devices) {
    return Unexpected(devices.error());
  }
  return selectDevice(*devices, index);
}

Expected<void, Error> checkBlockThreads(unsigned block_threads) {
  if (block_threads == 0 || block_threads > 1024 || block_threads % 32 != 0) {
    return fail(ErrorCode::kInvalidArgument,
                "CUDA block size must be a multiple of 32 from 32 to 1024 threads");
  }
  return {};
}

Result<DeviceInfo> selectDevice(const std::vector<DeviceInfo>& devices, int index) {
  const int wanted = index < 0 ? 0 : index;
  for (const DeviceInfo& d : devices) {
    if (d.index == wanted) {
      return d;
    }
  }
  std::string known;
  for (const DeviceInfo& d : devices) {
    known += (known.empty() ? "" : ", ") + std::to_string(d.index) + " (" + d.name + ")";
  }
  return fail(ErrorCode::kInvalidArgument, "backend.cuda_device: " + std::to_string(wanted) +
                                               ": no such CUDA device; this machine has " +
                                               (known.empty() ? std::string("none") : known));
}

}  // namespace raymap::cuda
