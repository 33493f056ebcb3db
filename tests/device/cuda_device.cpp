// SPDX-License-Identifier: BSD-3-Clause
// The shared device tests against the CUDA backend (skipped, exit code 77, without a CUDA device).
#include <cstdlib>
#include <string>

#include "src/device/cuda/cuda_backend.hpp"
#include "src/device/cuda/cuda_devices.hpp"
#include "src/device/cuda/cuda_heightmap.hpp"
#include "tests/device/device_under_test.hpp"

namespace raymap::test {
namespace {

std::string unavailable() {
  auto devices = cuda::listDevices();
  return devices ? std::string() : devices.error().message;
}

/// RAYMAP_TEST_CUDA_MAPPED=1 (the device kit's second run of the suite): the shared-memory tests
/// run on a discrete GPU too, through mapped page-locked host memory: the Jetson's code path.
bool mappedOnDiscrete() {
  const char* mapped = std::getenv("RAYMAP_TEST_CUDA_MAPPED");
  return mapped != nullptr && std::string(mapped) == "1";
}

Result<std::unique_ptr<Backend>> create(VoxelMap& map, const DeviceBackendOptions& shared) {
  CudaBackendOptions options;
  static_cast<DeviceBackendOptions&>(options) = shared;
  options.map_host_memory_on_discrete = mappedOnDiscrete();
  return createCudaBackend(map, options);
}

bool cudaSharesMemory() {
  auto devices = cuda::listDevices();
  return devices && !devices->empty() && (devices->front().integrated || mappedOnDiscrete()) &&
         devices->front().can_map_host_memory;
}

Result<std::unique_ptr<heightmap::HeightmapGenerator>> createHeightmap(Backend& backend) {
  return createCudaHeightmapGenerator(backend);
}

}  // namespace

const DeviceUnderTest& deviceUnderTest() {
  static const DeviceUnderTest device{"CUDA", &unavailable, &create, &cudaSharesMemory,
                                      &createHeightmap};
  return device;
}

}  // namespace raymap::test
