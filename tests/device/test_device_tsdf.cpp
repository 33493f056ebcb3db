// SPDX-License-Identifier: BSD-3-Clause
// TSDF maps on a device backend: against the CPU reference on the simulated sphere and box, in
// both walk directions, with the region cache and shared memory, with no update dropped; and the
// surface the device builds lies where the CPU's does. Written once; linked into one executable
// per GPU API (test_unit_opencl runs it on PoCL in CI; test_cuda_device on an NVIDIA GPU).
#include <cstdio>
#include <iostream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "src/map/tsdf_surface.hpp"
#include "tests/device/device_under_test.hpp"
#include "tests/support/test_rays.hpp"
#include "tests/support/tsdf_scenes.hpp"

namespace raymap::test {
namespace {

// A voxel's rays land in another order on the device than on the CPU: the averages differ by
// float rounding, and OpenCL's sqrt (3 ulp) moves distances by about 1e-7 m.
constexpr double kDistanceTolerance = 1e-4;  // metres
constexpr double kWeightTolerance = 1e-4;    // relative
constexpr double kTsdfMinAgreement = 0.999;

TEST(DeviceTsdf, AgreesWithTheCpuReferenceOnASphereAndABox) {
  REQUIRE_DEVICE();
  for (const TsdfScene& scene : {sphereScene(3000), boxScene(3000, 0.3)}) {
    for (const bool reverse : {false, true}) {
      // Arrange
      RayFilter filter;
      filter.reverse = reverse;
      VoxelMap reference = makeMap(tsdfConfig());
      auto cpu = cpuBackend(reference, 1);
      integrate(reference, *cpu, scene.rays, filter);
      for (DeviceMemory memory : {DeviceMemory::kCache, DeviceMemory::kShared}) {
        if (memory == DeviceMemory::kShared && !deviceUnderTest().shares_memory()) {
          continue;
        }
        VoxelMap map = makeMap(tsdfConfig());
        DeviceBackendOptions options;
        options.memory = memory;
        auto device = createDeviceBackend(map, options);
        ASSERT_TRUE(device);

        // Act
        integrate(map, *device, scene.rays, filter);
        ASSERT_TRUE(device->synchronise());
        const TsdfComparison cmp =
            compareTsdf(reference, map, kDistanceTolerance, kWeightTolerance);

        // Assert
        const std::string label = scene.name + (reverse ? ", reverse" : ", forward") +
                                  (memory == DeviceMemory::kCache ? ", region cache" : ", shared");
        std::printf(
            "[device-tsdf] %s %s: %.4f %% of %llu voxels within tolerance, max "
            "difference %.3g m / weight %.3g; dropped %llu\n",
            deviceUnderTest().api, label.c_str(),
            100.0 * double(cmp.within) / double(std::max<std::uint64_t>(cmp.updated, 1)),
            static_cast<unsigned long long>(cmp.updated), cmp.max_distance_difference,
            cmp.max_weight_difference,
            static_cast<unsigned long long>(device->stats().updates_dropped));
        EXPECT_GT(cmp.updated, 5000u) << label;
        EXPECT_GE(double(cmp.within), kTsdfMinAgreement * double(cmp.updated)) << label;
        EXPECT_EQ(device->stats().updates_dropped, 0u) << label;
        EXPECT_EQ(device->stats().rays_skipped, 0u) << label;
      }
    }
  }
}

TEST(DeviceTsdf, TheSurfaceIsWhereTheCpuPutsIt) {
  REQUIRE_DEVICE();
  const TsdfScene scene = sphereScene(6000);
  VoxelMap reference = makeMap(tsdfConfig());
  auto cpu = cpuBackend(reference, 1);
  integrate(reference, *cpu, scene.rays);
  VoxelMap map = makeMap(tsdfConfig());
  auto device = createDeviceBackend(map);
  ASSERT_TRUE(device);
  integrate(map, *device, scene.rays);
  ASSERT_TRUE(device->synchronise());
  const auto expected = tsdfZeroCrossings(reference, 20.0f);
  const auto got = tsdfZeroCrossings(map, 20.0f);
  ASSERT_GT(expected.size(), 300u);
  // Weights may straddle the threshold by rounding: nearly the same crossings, each where the
  // CPU's is.
  EXPECT_NEAR(double(got.size()), double(expected.size()), 0.01 * double(expected.size()));
  double worst = 0.0;
  for (const TsdfSurfacePoint& p : got) {
    worst = std::max(worst, std::fabs(scene.truth(p.p_world)));
  }
  std::printf("[device-tsdf] %s: %zu crossings, worst %.3f voxel from the sphere\n",
              deviceUnderTest().api, got.size(), worst / 0.1);
  EXPECT_LE(worst, 0.05);  // the CPU's worst at this weight is about 0.3 voxel; 0.5 voxel at most
}

}  // namespace
}  // namespace raymap::test
