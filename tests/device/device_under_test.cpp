// SPDX-License-Identifier: BSD-3-Clause
#include "tests/device/device_under_test.hpp"

#include <cstdlib>

#include "src/map/ray_preparer.hpp"
#include "tests/support/test_rays.hpp"

namespace raymap::test {

std::unique_ptr<Backend> createDeviceBackend(VoxelMap& map, const DeviceBackendOptions& options) {
  DeviceBackendOptions chosen = options;
  // CTest runs suites again with the batches planned on the device (tests/CMakeLists.txt): the
  // maps must not change.
  if (const char* planning = std::getenv("RAYMAP_TEST_DEVICE_PLANNING")) {
    chosen.planning = gpu::planningNamed(planning).value_or(gpu::Planning::kHost);
  }
  return createDeviceBackendAsGiven(map, chosen);
}

std::unique_ptr<Backend> createDeviceBackendAsGiven(VoxelMap& map,
                                                    const DeviceBackendOptions& options) {
  auto backend = deviceUnderTest().create(map, options);
  EXPECT_TRUE(backend) << deviceUnderTest().api << ": " << (backend ? "" : backend.error().message);
  return backend ? std::move(*backend) : nullptr;
}

bool devicePreparesRays() {
  VoxelMap map = makeMap(smallConfig(Semantics::kPerRay));
  DeviceBackendOptions options;
  options.planning = gpu::Planning::kDevice;
  auto backend = createDeviceBackendAsGiven(map, options);
  return backend && backend->preparesOnDevice(RayFilter{});
}

}  // namespace raymap::test
