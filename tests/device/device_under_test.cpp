// SPDX-License-Identifier: BSD-3-Clause
#include "tests/device/device_under_test.hpp"

#include <cstdlib>

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

}  // namespace raymap::test
