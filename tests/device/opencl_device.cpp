// SPDX-License-Identifier: BSD-3-Clause
// The shared device tests against the OpenCL backend (PoCL in CI).
#include <cstdlib>

#include "src/device/opencl/cl_runtime.hpp"
#include "src/device/opencl/opencl_backend.hpp"
#include "src/device/opencl/opencl_heightmap.hpp"
#include "tests/device/device_under_test.hpp"

namespace raymap::test {
namespace {

std::string unavailable() {
  auto devices = opencl::listDevices();
  if (!devices || devices->empty()) {
    return "no OpenCL platform (install pocl-opencl-icd to run)";
  }
  return {};
}

Result<std::unique_ptr<Backend>> create(VoxelMap& map, const DeviceBackendOptions& shared) {
  OpenClBackendOptions options;
  static_cast<DeviceBackendOptions&>(options) = shared;
  options.program_cache.directory = ::testing::TempDir() + "raymap-opencl-test-cache";
  // CTest runs the agreement suites a second time with span work per span (tests/CMakeLists.txt):
  // on a CPU device the default is per region, and both must agree with the CPU.
  if (const char* work = std::getenv("RAYMAP_TEST_OPENCL_SPAN_WORK")) {
    options.span_work = spanWorkNamed(work).value_or(SpanWork::kAuto);
  }
  return createOpenClBackend(map, options);
}

bool openclSharesMemory() {
  auto devices = opencl::listDevices();
  if (!devices) {
    return false;
  }
  auto device = opencl::selectDevice(*devices, opencl::DeviceSelector{});
  return device && device->unified_memory;
}

Result<std::unique_ptr<heightmap::HeightmapGenerator>> createHeightmap(Backend& backend) {
  return createOpenClHeightmapGenerator(backend, {});
}

}  // namespace

const DeviceUnderTest& deviceUnderTest() {
  static const DeviceUnderTest device{"OpenCL", &unavailable, &create, &openclSharesMemory,
                                      &createHeightmap};
  return device;
}

}  // namespace raymap::test
