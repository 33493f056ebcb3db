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

#include "kernels/common/map_mode.h"
#include "src/device/opencl/opencl_backend.hpp"
#include "src/device/staging/staged_backend.hpp"
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

// Each device program is built (OpenCL) or instantiated (CUDA) for the map modes of
// kernels/common/map_mode.h only. Every map configuration the library accepts must have one:
// otherwise a valid map would be refused by the devices at start-up.
TEST(MapModeKernels, EveryMapTheLibraryAcceptsHasDeviceKernels) {
  int accepted = 0;
  std::set<std::uint32_t> modes;
  for (const MapMode mode :
       {MapMode::kOccupancy, MapMode::kNdtOm, MapMode::kNdtTm, MapMode::kTsdf}) {
    for (const Semantics semantics : {Semantics::kPerRay, Semantics::kPerScan}) {
      for (const int layers : {0, 1, 2, 3, 4, 5, 6, 7}) {
        MapConfig config = test::smallConfig(semantics);
        config.mode = mode;
        config.voxel_mean = (layers & 1) != 0;
        config.decay_rate = (layers & 2) != 0;
        config.occupancy_layer = (layers & 4) != 0;
        config.memory_budget_bytes = std::uint64_t{64} << 20;
        auto map = VoxelMap::create(config);
        if (!map) {
          continue;  // a configuration validate() refuses
        }
        ++accepted;
        const std::uint32_t bits = gpu::mapModeBits(*map);
        modes.insert(bits);
        EXPECT_TRUE(rm_map_mode_has_kernels(bits))
            << mapModeName(config) << ", semantics " << static_cast<int>(semantics) << ", layers "
            << layers << ": mode bits " << bits;
      }
    }
  }
  // Occupancy per ray and per scan with and without decay rates, decay rates alone, TSDF, NDT
  // with and without decay rates: the eight modes the programs have kernels for.
  EXPECT_GE(accepted, 8);
  EXPECT_EQ(modes.size(), 8u);
}

TEST(MapModeKernels, ModeBitsFollowTheLayers) {
  EXPECT_EQ(rm_map_mode_bits(1u, 0u, 0u, 0u, 0u), RM_MODE_OCCUPANCY);
  EXPECT_EQ(rm_map_mode_bits(1u, 1u, 1u, 0u, 0u),
            RM_MODE_OCCUPANCY | RM_MODE_PER_SCAN | RM_MODE_TRAVERSAL);
  EXPECT_EQ(rm_map_mode_bits(0u, 0u, 0u, 1u, 0u), RM_MODE_TSDF);
  EXPECT_EQ(rm_map_mode_bits(1u, 0u, 1u, 0u, 1u),
            RM_MODE_NDT | RM_MODE_OCCUPANCY | RM_MODE_TRAVERSAL);
  EXPECT_FALSE(rm_map_mode_has_kernels(RM_MODE_NDT | RM_MODE_PER_SCAN | RM_MODE_OCCUPANCY));
  EXPECT_FALSE(rm_map_mode_has_kernels(RM_MODE_TSDF | RM_MODE_OCCUPANCY));
  EXPECT_FALSE(rm_map_mode_has_kernels(0u));
}

TEST(OpenClBackend, PerScanMapWithoutScanMarksIsRefusedWithAClearError) {
  if (!opencl::listDevices()) {
    GTEST_SKIP() << "no OpenCL platform (install pocl-opencl-icd to run)";
  }
  MapConfig config = test::smallConfig(Semantics::kPerScan);
  config.device_scan_marks = false;  // a map made for the CPU backend
  VoxelMap map = test::makeMap(config);
  OpenClBackendOptions options;
  options.program_cache.enabled = false;
  auto backend = createOpenClBackend(map, options);
  ASSERT_FALSE(backend);
  EXPECT_EQ(backend.error().code, ErrorCode::kUnsupported);
  EXPECT_NE(backend.error().message.find("device_scan_marks"), std::string::npos)
      << backend.error().message;
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

// Span work (docs/architecture.md, "Span work on CPU devices"): a CPU device (PoCL in CI) gives
// each region to one work-item unless asked otherwise; a GPU keeps one work-item per span.
TEST(OpenClBackend, SpanWorkIsPerRegionOnCpuDevicesUnlessAskedOtherwise) {
  auto devices = opencl::listDevices();
  if (!devices || devices->empty()) {
    GTEST_SKIP() << "no OpenCL platform (install pocl-opencl-icd to run)";
  }
  auto device = opencl::selectDevice(*devices, opencl::DeviceSelector{});
  ASSERT_TRUE(device);
  const bool cpu_device = device->type == "CPU";
  for (const SpanWork work : {SpanWork::kAuto, SpanWork::kPerSpan, SpanWork::kPerRegion}) {
    VoxelMap map = test::makeMap(test::smallConfig(Semantics::kPerRay));
    OpenClBackendOptions options;
    options.span_work = work;
    auto backend = openClBackend(map, options);
    ASSERT_TRUE(backend);
    const bool by_region = work == SpanWork::kPerRegion || (work == SpanWork::kAuto && cpu_device);
    EXPECT_EQ(backend->deviceName().find("span work per region") != std::string::npos, by_region)
        << backend->deviceName();
  }
}

// Both ways of sharing out the spans give the map the CPU reference gives, bit for bit, in both
// semantics (voxel means included); the agreement suites (tests/device) run per region on PoCL,
// and the opencl.span_work_per_span entries of CTest run them again per span.
TEST(OpenClBackend, SpanWorkPerSpanAndPerRegionGiveTheSameMap) {
  if (!opencl::listDevices()) {
    GTEST_SKIP() << "no OpenCL platform (install pocl-opencl-icd to run)";
  }
  const std::vector<Ray> rays = test::randomScans(77, 3, 3000);
  for (const Semantics semantics : {Semantics::kPerRay, Semantics::kPerScan}) {
    VoxelMap reference = test::makeMap(test::smallConfig(semantics));
    auto cpu = test::cpuBackend(reference, 1);
    test::integrate(reference, *cpu, rays);
    for (const SpanWork work : {SpanWork::kPerSpan, SpanWork::kPerRegion}) {
      VoxelMap map = test::makeMap(test::smallConfig(semantics));
      OpenClBackendOptions options;
      options.span_work = work;
      auto backend = openClBackend(map, options);
      ASSERT_TRUE(backend);
      test::integrate(map, *backend, rays);
      ASSERT_TRUE(backend->synchronise());
      const test::MapComparison cmp = test::compareMaps(reference, map);
      const char* label = work == SpanWork::kPerSpan ? "per span" : "per region";
      EXPECT_GT(cmp.compared, 10000u) << label;
      EXPECT_EQ(cmp.exact_value, cmp.compared) << label;
      EXPECT_EQ(backend->stats().voxels_visited, cpu->stats().voxels_visited) << label;
      EXPECT_EQ(backend->stats().updates_dropped, 0u) << label;
    }
  }
}

}  // namespace
}  // namespace raymap
