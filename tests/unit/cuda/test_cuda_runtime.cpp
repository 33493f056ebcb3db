// SPDX-License-Identifier: BSD-3-Clause
// The CUDA backend on any machine: device discovery either finds devices or says why not (no
// driver, no device), and bad options are refused before any device is touched. These run in CI
// without a GPU; the agreement tests (tests/device, test_cuda_device) need one.
#include <gtest/gtest.h>

#include "src/device/cuda/cuda_backend.hpp"
#include "src/device/cuda/cuda_devices.hpp"
#include "tests/support/test_rays.hpp"

namespace raymap {
namespace {

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

TEST(CudaDevices, ListEitherFindsDevicesOrSaysWhyNot) {
  auto devices = cuda::listDevices();
  if (!devices) {
    // This machine has no driver or no GPU (CI): the message must tell the user which.
    const std::string& message = devices.error().message;
    EXPECT_TRUE(contains(message, "no CUDA driver") || contains(message, "no CUDA device") ||
                contains(message, "CUDA device discovery"))
        << message;
    return;
  }
  ASSERT_FALSE(devices->empty());
  for (const cuda::DeviceInfo& d : *devices) {
    EXPECT_FALSE(d.name.empty());
    EXPECT_GT(d.global_mem_bytes, 0u);
    EXPECT_GT(d.multiprocessors, 0u);
    // CUDA 13 builds code for compute capability 7.5 and later only.
    EXPECT_GE(d.compute_major * 10 + d.compute_minor, 75) << d.name;
    EXPECT_GT(d.runtime_version, 0);
  }
}

TEST(CudaDevices, SelectingAMissingOrdinalNamesItAndWhatExists) {
  std::vector<cuda::DeviceInfo> devices(2);
  devices[0].index = 0;
  devices[0].name = "first";
  devices[1].index = 1;
  devices[1].name = "second";
  auto picked = cuda::selectDevice(devices, 1);
  ASSERT_TRUE(picked);
  EXPECT_EQ(picked->name, "second");
  auto by_default = cuda::selectDevice(devices, -1);
  ASSERT_TRUE(by_default);
  EXPECT_EQ(by_default->name, "first");
  auto missing = cuda::selectDevice(devices, 7);
  ASSERT_FALSE(missing);
  EXPECT_TRUE(contains(missing.error().message, "backend.cuda_device: 7"))
      << missing.error().message;
  EXPECT_TRUE(contains(missing.error().message, "1 (second)")) << missing.error().message;
}

TEST(CudaDevices, VersionsReadAsMajorDotMinor) {
  EXPECT_EQ(cuda::versionText(13000), "13.0");
  EXPECT_EQ(cuda::versionText(12060), "12.6");
  EXPECT_EQ(cuda::versionText(11040), "11.4");
}

TEST(CudaBackend, CreationFailsClearlyWithoutADeviceAndWorksWithOne) {
  VoxelMap map = test::makeMap(test::smallConfig(Semantics::kPerRay));
  auto backend = createCudaBackend(map, CudaBackendOptions{});
  if (!cuda::listDevices()) {
    ASSERT_FALSE(backend);
    EXPECT_TRUE(contains(backend.error().message, "CUDA")) << backend.error().message;
    return;
  }
  ASSERT_TRUE(backend) << backend.error().message;
  EXPECT_STREQ((*backend)->name(), "cuda");
  EXPECT_FALSE((*backend)->deviceName().empty());
}

TEST(CudaBackend, BadOptionsAreRefusedBeforeTheDeviceIsTouched) {
  VoxelMap map = test::makeMap(test::smallConfig(Semantics::kPerRay));
  CudaBackendOptions odd_block;
  odd_block.block_threads = 100;
  auto a = createCudaBackend(map, odd_block);
  ASSERT_FALSE(a);
  EXPECT_TRUE(contains(a.error().message, "block size")) << a.error().message;
  CudaBackendOptions no_batch;
  no_batch.batch_rays = 0;
  auto b = createCudaBackend(map, no_batch);
  ASSERT_FALSE(b);
  EXPECT_TRUE(contains(b.error().message, "CUDA batch sizes")) << b.error().message;
}

TEST(CudaBackend, UnknownDeviceOrdinalIsAClearError) {
  if (!cuda::listDevices()) {
    GTEST_SKIP() << "no CUDA device: the ordinal cannot be checked against a device list";
  }
  VoxelMap map = test::makeMap(test::smallConfig(Semantics::kPerRay));
  CudaBackendOptions options;
  options.device = 97;
  auto backend = createCudaBackend(map, options);
  ASSERT_FALSE(backend);
  EXPECT_TRUE(contains(backend.error().message, "backend.cuda_device: 97"))
      << backend.error().message;
}

}  // namespace
}  // namespace raymap
