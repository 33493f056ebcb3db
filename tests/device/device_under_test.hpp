// SPDX-License-Identifier: BSD-3-Clause
// The device backend a device test executable runs against. The tests in this folder are written
// once and linked into one executable per GPU API (OpenCL, CUDA) together with that API's
// definition of deviceUnderTest().
#pragma once

#include <memory>
#include <string>

#include "raymap/error.hpp"
#include <gtest/gtest.h>

#include "src/device/staging/device_options.hpp"
#include "src/heightmap/heightmap_generator.hpp"
#include "src/map/backend.hpp"
#include "src/map/voxel_map.hpp"

namespace raymap::test {

/// @brief One GPU API's backend, as the shared device tests see it.
struct DeviceUnderTest {
  const char* api = "";  ///< "OpenCL", "CUDA" (messages and reports)
  /// Why this machine cannot run the backend ("" when it can): the tests skip with it.
  std::string (*unavailable)() = nullptr;
  /// Creates the backend with the shared options and the API's defaults for the rest.
  Result<std::unique_ptr<Backend>> (*create)(VoxelMap& map,
                                             const DeviceBackendOptions& options) = nullptr;
  /// Whether the device can work on the host map in place (DeviceMemory::kShared).
  bool (*shares_memory)() = nullptr;
  /// Creates the API's height-map generator in the context of `backend` (one of this API's).
  Result<std::unique_ptr<heightmap::HeightmapGenerator>> (*create_heightmap)(Backend& backend) =
      nullptr;
};

/// @brief Defined once per executable by the API's file (opencl_device.cpp, cuda_device.cpp).
const DeviceUnderTest& deviceUnderTest();

/// @brief The backend, with a test failure (and nullptr) when creation fails. Planning follows
/// RAYMAP_TEST_DEVICE_PLANNING ("host", "device") where it is set (CTest's device-planning runs).
std::unique_ptr<Backend> createDeviceBackend(VoxelMap& map,
                                             const DeviceBackendOptions& options = {});
/// @brief createDeviceBackend() with the options exactly as given (planning included).
std::unique_ptr<Backend> createDeviceBackendAsGiven(VoxelMap& map,
                                                    const DeviceBackendOptions& options);
/// @brief Whether the device, planning on the device, prepares and deskews rays there (double
/// precision: every CUDA device, OpenCL devices with cl_khr_fp64 such as PoCL's).
bool devicePreparesRays();

}  // namespace raymap::test

/// Skips the test where the device under test cannot prepare rays (devicePreparesRays()).
#define REQUIRE_DEVICE_PREPARATION()                                         \
  REQUIRE_DEVICE();                                                          \
  if (!::raymap::test::devicePreparesRays()) {                               \
    GTEST_SKIP() << "the device has no double precision: the host prepares"; \
  }

/// Skips the test, with the reason, when the machine cannot run the device under test.
#define REQUIRE_DEVICE()                                                                       \
  if (const std::string why = ::raymap::test::deviceUnderTest().unavailable(); !why.empty()) { \
    GTEST_SKIP() << why;                                                                       \
  }
