// SPDX-License-Identifier: BSD-3-Clause
// What only the OpenCL backend has: 32-bit counters, kernel build errors, device selectors. The
// agreement with the CPU reference is tests/device/test_device_backend.cpp, linked into this
// executable too. Runs for real on PoCL; skips without a platform.
#include <cstring>
#include <random>
#include <set>
#include <tuple>
#include <vector>

#include <gtest/gtest.h>

#include "src/device/opencl/opencl_backend.hpp"
#include "src/io/map_file.hpp"
#include "tests/support/temp_dir.hpp"
#include "tests/support/test_rays.hpp"
#include "tests/support/tsdf_scenes.hpp"

namespace raymap {
namespace {

using test::makeRay;

/// An OpenCL backend, or a skip when this machine has no OpenCL platform (never a silent pass).
std::unique_ptr<Backend> openClBackend(VoxelMap& map, OpenClBackendOptions options = {}) {
  auto devices = opencl::listDevices();
  if (!devices) {
    return nullptr;
  }
  options.program_cache.directory = ::testing::TempDir() + "raymap-opencl-test-cache";
  auto backend = createOpenClBackend(map, options);
  EXPECT_TRUE(backend) << (backend ? "" : backend.error().message);
  return backend ? std::move(*backend) : nullptr;
}

#define REQUIRE_OPENCL(backend)                                            \
  if (!(backend)) {                                                        \
    GTEST_SKIP() << "no OpenCL platform (install pocl-opencl-icd to run)"; \
  }

TEST(OpenClBackend, ThirtyTwoBitCountersGiveTheSameMap) {
  const std::vector<Ray> rays = test::randomScans(21, 2, 3000);
  VoxelMap a = test::makeMap(test::smallConfig(Semantics::kPerScan));
  VoxelMap b = test::makeMap(test::smallConfig(Semantics::kPerScan));
  auto wide = openClBackend(a);
  REQUIRE_OPENCL(wide);
  OpenClBackendOptions narrow_options;
  narrow_options.force_32bit_atomics = true;
  auto narrow = openClBackend(b, narrow_options);
  ASSERT_TRUE(narrow);
  test::integrate(a, *wide, rays);
  test::integrate(b, *narrow, rays);
  ASSERT_TRUE(wide->synchronise());
  ASSERT_TRUE(narrow->synchronise());
  const test::MapComparison cmp = test::compareMaps(a, b);
  EXPECT_EQ(cmp.exact_value, cmp.compared);
  EXPECT_EQ(wide->stats().voxels_visited, narrow->stats().voxels_visited);
}

// Without 64-bit atomics the (distance, weight) pair of a TSDF voxel is updated under a lock bit
// in its weight word (kernels/device/tsdf.h): the same field as the CPU's, nothing dropped. The
// rays are walked from the sample back (the device default), as a robot's would be.
TEST(OpenClBackend, TsdfWithoutSixtyFourBitAtomicsAgreesWithTheCpu) {
  const test::TsdfScene scene = test::sphereScene(3000);
  RayFilter reverse;
  reverse.reverse = true;
  VoxelMap reference = test::makeMap(test::tsdfConfig());
  auto cpu = test::cpuBackend(reference, 1);
  test::integrate(reference, *cpu, scene.rays, reverse);
  VoxelMap map = test::makeMap(test::tsdfConfig());
  OpenClBackendOptions narrow_options;
  narrow_options.force_32bit_atomics = true;
  auto narrow = openClBackend(map, narrow_options);
  REQUIRE_OPENCL(narrow);
  test::integrate(map, *narrow, scene.rays, reverse);
  ASSERT_TRUE(narrow->synchronise());
  const test::TsdfComparison cmp = test::compareTsdf(reference, map, 1e-4, 1e-4);
  EXPECT_GT(cmp.updated, 5000u);
  EXPECT_GE(double(cmp.within), 0.999 * double(cmp.updated));
  EXPECT_EQ(narrow->stats().updates_dropped, 0u);
}

TEST(OpenClBackend, KernelBuildFailureIsAClearError) {
  if (!opencl::listDevices()) {
    GTEST_SKIP() << "no OpenCL platform (install pocl-opencl-icd to run)";
  }
  VoxelMap map = test::makeMap(test::smallConfig(Semantics::kPerRay));
  OpenClBackendOptions options;
  options.program_cache.enabled = false;
  options.extra_build_options = "-Dcount=)";  // breaks the kernel source
  auto backend = createOpenClBackend(map, options);
  ASSERT_FALSE(backend);
  EXPECT_NE(backend.error().message.find("build"), std::string::npos) << backend.error().message;
}

TEST(OpenClBackend, UnknownDeviceIsAClearError) {
  if (!opencl::listDevices()) {
    GTEST_SKIP() << "no OpenCL platform (install pocl-opencl-icd to run)";
  }
  VoxelMap map = test::makeMap(test::smallConfig(Semantics::kPerRay));
  OpenClBackendOptions options;
  options.device.device = "no-such-device-anywhere";
  auto backend = createOpenClBackend(map, options);
  ASSERT_FALSE(backend);
  EXPECT_NE(backend.error().message.find("no-such-device-anywhere"), std::string::npos);
}

}  // namespace
}  // namespace raymap
