// SPDX-License-Identifier: BSD-3-Clause
#include "tests/device/device_under_test.hpp"

namespace raymap::test {

std::unique_ptr<Backend> createDeviceBackend(VoxelMap& map, const DeviceBackendOptions& options) {
  auto backend = deviceUnderTest().create(map, options);
  EXPECT_TRUE(backend) << deviceUnderTest().api << ": " << (backend ? "" : backend.error().message);
  return backend ? std::move(*backend) : nullptr;
}

}  // namespace raymap::test
