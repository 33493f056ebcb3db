// SPDX-License-Identifier: BSD-3-Clause
// OpenCL runtime helpers: device listing and selection, contexts, buffers, kernels and the
// program binary cache. Tests that need a device skip (CTest: "Skipped") when no platform exists.
#include <algorithm>
#include <cctype>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "src/device/opencl/cl_runtime.hpp"
#include "src/device/opencl/program_cache.hpp"
#include "tests/support/temp_dir.hpp"

namespace raymap::opencl {
namespace {

using test::TempDir;

constexpr const char* kAddOneSource = R"CL(
__kernel void add_one(__global int* values) {
  const size_t i = get_global_id(0);
  values[i] = values[i] + 1;
}
)CL";

DeviceInfo fakeDevice(std::uint32_t platform, std::uint32_t device, std::string platform_name,
                      std::string device_name, std::string type) {
  DeviceInfo d;
  d.platform_index = platform;
  d.device_index = device;
  d.platform_name = std::move(platform_name);
  d.device_name = std::move(device_name);
  d.type = std::move(type);
  return d;
}

// Two platforms, the GPU on the second: the default must look past the first platform's CPU.
std::vector<DeviceInfo> fakeDevices() {
  return {fakeDevice(0, 0, "Portable Computing Language", "pthread-cpu", "CPU"),
          fakeDevice(1, 0, "Intel(R) OpenCL Graphics", "Intel(R) UHD Graphics 770", "GPU"),
          fakeDevice(1, 1, "Intel(R) OpenCL Graphics", "Intel(R) Arc A380", "GPU")};
}

TEST(ClRuntime, ErrorNameCoversKnownAndUnknownCodes) {
  EXPECT_STREQ(errorName(CL_SUCCESS), "CL_SUCCESS");
  EXPECT_STREQ(errorName(CL_OUT_OF_RESOURCES), "CL_OUT_OF_RESOURCES");
  EXPECT_STREQ(errorName(CL_INVALID_KERNEL_NAME), "CL_INVALID_KERNEL_NAME");
  EXPECT_STREQ(errorName(-1001), "CL_PLATFORM_NOT_FOUND_KHR");
  EXPECT_STREQ(errorName(-12345), "CL_ERROR(-12345)");
}

TEST(ClRuntimeSelect, DefaultPrefersTheFirstGpu) {
  auto d = selectDevice(fakeDevices(), {});
  ASSERT_TRUE(d) << d.error().message;
  EXPECT_EQ(d->device_name, "Intel(R) UHD Graphics 770");
}

TEST(ClRuntimeSelect, DefaultFallsBackToTheFirstDeviceOfThePlatform) {
  auto d = selectDevice(fakeDevices(), {"portable", ""});
  ASSERT_TRUE(d) << d.error().message;
  EXPECT_EQ(d->device_name, "pthread-cpu");
}

TEST(ClRuntimeSelect, PlatformAndDeviceByIndex) {
  auto d = selectDevice(fakeDevices(), {"1", "1"});
  ASSERT_TRUE(d) << d.error().message;
  EXPECT_EQ(d->device_name, "Intel(R) Arc A380");
}

TEST(ClRuntimeSelect, DeviceBySubstringIgnoresCase) {
  auto d = selectDevice(fakeDevices(), {"", "arc a3"});
  ASSERT_TRUE(d) << d.error().message;
  EXPECT_EQ(d->platform_index, 1u);
  EXPECT_EQ(d->device_index, 1u);
}

TEST(ClRuntimeSelect, DeviceIndexOnSeveralPlatformsIsAmbiguous) {
  auto d = selectDevice(fakeDevices(), {"", "0"});
  ASSERT_FALSE(d);
  EXPECT_EQ(d.error().code, ErrorCode::kInvalidArgument);
  EXPECT_NE(d.error().message.find("several platforms"), std::string::npos) << d.error().message;
}

TEST(ClRuntimeSelect, UnknownPlatformListsWhatExists) {
  auto d = selectDevice(fakeDevices(), {"nvidia", ""});
  ASSERT_FALSE(d);
  EXPECT_NE(d.error().message.find("platform 1 device 1: Intel(R) Arc A380"), std::string::npos)
      << d.error().message;
}

TEST(ClRuntimeSelect, EmptyListFails) {
  auto d = selectDevice({}, {});
  ASSERT_FALSE(d);
}

// Everything below needs a real OpenCL platform (PoCL in CI).
class ClDevice : public ::testing::Test {
 protected:
  void SetUp() override {
    auto devices = listDevices();
    if (!devices) {
      GTEST_SKIP() << devices.error().message;
    }
    devices_ = *devices;
    auto device = selectDevice(devices_, {});
    ASSERT_TRUE(device) << device.error().message;
    auto ctx = createContext(*device);
    ASSERT_TRUE(ctx) << ctx.error().message;
    ctx_ = std::move(*ctx);
  }

  Result<BuiltProgram> build(const std::string& source, const std::string& dir,
                             const std::string& options = "-cl-std=CL1.2") {
    ProgramCacheOptions cache;
    cache.directory = dir;
    return buildProgram(ctx_, source, options, cache);
  }

  // Runs add_one over {1, 2, 3, 4}: proves that a program (cached or not) really executes.
  std::vector<cl_int> runAddOne(const ProgramHandle& program) {
    std::vector<cl_int> values = {1, 2, 3, 4};
    const std::size_t bytes = values.size() * sizeof(cl_int);
    auto kernel = createKernel(program, "add_one");
    auto buffer = createBuffer(ctx_, bytes, "test values");
    if (!kernel || !buffer) {
      ADD_FAILURE() << (kernel ? buffer.error().message : kernel.error().message);
      return {};
    }
    cl_mem mem = buffer->get();
    const std::size_t global = values.size();
    const bool ok = clEnqueueWriteBuffer(ctx_.queue.get(), mem, CL_TRUE, 0, bytes, values.data(), 0,
                                         nullptr, nullptr) == CL_SUCCESS &&
                    clSetKernelArg(kernel->get(), 0, sizeof(mem), &mem) == CL_SUCCESS &&
                    clEnqueueNDRangeKernel(ctx_.queue.get(), kernel->get(), 1, nullptr, &global,
                                           nullptr, 0, nullptr, nullptr) == CL_SUCCESS &&
                    clEnqueueReadBuffer(ctx_.queue.get(), mem, CL_TRUE, 0, bytes, values.data(), 0,
                                        nullptr, nullptr) == CL_SUCCESS;
    EXPECT_TRUE(ok);
    return values;
  }

  std::vector<DeviceInfo> devices_;
  DeviceContext ctx_;
};

TEST_F(ClDevice, ListsAtLeastOneSaneDevice) {
  ASSERT_FALSE(devices_.empty());
  for (const DeviceInfo& d : devices_) {
    EXPECT_FALSE(d.device_name.empty());
    EXPECT_NE(d.device_name.front(), ' ');
    EXPECT_NE(d.device_name.back(), ' ');
    EXPECT_FALSE(d.platform_name.empty());
    EXPECT_NE(d.platform, nullptr);
    EXPECT_NE(d.device, nullptr);
    EXPECT_EQ(d.opencl_c_version.rfind("OpenCL C", 0), 0u) << d.opencl_c_version;
    EXPECT_TRUE(d.type == "GPU" || d.type == "CPU" || d.type == "accelerator" || d.type == "other");
    EXPECT_GT(d.compute_units, 0u);
    EXPECT_GT(d.global_mem_bytes, 0u);
    EXPECT_GT(d.max_alloc_bytes, 0u);
    EXPECT_LE(d.max_alloc_bytes, d.global_mem_bytes);
    EXPECT_GT(d.max_work_group_size, 0u);
  }
}

TEST_F(ClDevice, SelectsByIndexAndByCaseFlippedSubstring) {
  const DeviceInfo& first = devices_.front();
  auto by_index = selectDevice(
      devices_, {std::to_string(first.platform_index), std::to_string(first.device_index)});
  ASSERT_TRUE(by_index) << by_index.error().message;
  EXPECT_EQ(by_index->device, first.device);

  std::string part =
      first.device_name.substr(0, std::min<std::size_t>(first.device_name.size(), 6));
  for (char& c : part) {
    const auto u = static_cast<unsigned char>(c);
    c = static_cast<char>(std::islower(u) != 0 ? std::toupper(u) : std::tolower(u));
  }
  std::string platform_part = first.platform_name.substr(0, 4);
  for (char& c : platform_part) {
    c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  }
  auto by_name = selectDevice(devices_, {platform_part, part});
  ASSERT_TRUE(by_name) << by_name.error().message;
  EXPECT_EQ(by_name->platform_index, first.platform_index);
  EXPECT_NE(by_name->device_name.find(first.device_name.substr(0, part.size())), std::string::npos);
}

TEST_F(ClDevice, BadSelectorsNameTheAvailableDevices) {
  const DeviceInfo& first = devices_.front();
  const std::string expected = "platform " + std::to_string(first.platform_index) + " device " +
                               std::to_string(first.device_index) + ": " + first.device_name;
  for (const DeviceSelector& selector :
       {DeviceSelector{"0", "99"}, DeviceSelector{"", "no-such-device-xyz"},
        DeviceSelector{"7", ""}}) {
    auto d = selectDevice(devices_, selector);
    ASSERT_FALSE(d);
    EXPECT_EQ(d.error().code, ErrorCode::kInvalidArgument);
    EXPECT_NE(d.error().message.find(expected), std::string::npos) << d.error().message;
  }
}

TEST_F(ClDevice, SecondBuildLoadsTheCachedBinary) {
  TempDir dir;
  auto first = build(kAddOneSource, dir.path().string());
  ASSERT_TRUE(first) << first.error().message;
  EXPECT_FALSE(first->from_cache);
  EXPECT_TRUE(first->warning.empty()) << first->warning;
  ASSERT_FALSE(first->cache_path.empty());
  EXPECT_TRUE(std::filesystem::exists(first->cache_path));

  auto second = build(kAddOneSource, dir.path().string());
  ASSERT_TRUE(second) << second.error().message;
  EXPECT_TRUE(second->from_cache);
  EXPECT_EQ(second->cache_path, first->cache_path);
  EXPECT_EQ(runAddOne(second->program), (std::vector<cl_int>{2, 3, 4, 5}));
}

TEST_F(ClDevice, OtherOptionsUseAnotherCacheFile) {
  TempDir dir;
  auto plain = build(kAddOneSource, dir.path().string());
  auto defined = build(kAddOneSource, dir.path().string(), "-cl-std=CL1.2 -DUNUSED=1");
  ASSERT_TRUE(plain) << plain.error().message;
  ASSERT_TRUE(defined) << defined.error().message;
  EXPECT_FALSE(defined->from_cache);
  EXPECT_NE(plain->cache_path, defined->cache_path);
}

TEST_F(ClDevice, SyntaxErrorFailsWithTheBuildLog) {
  TempDir dir;
  auto built = build("__kernel void broken(__global int* v) { v[0] = undeclared_name; }",
                     dir.path().string());
  ASSERT_FALSE(built);
  EXPECT_EQ(built.error().code, ErrorCode::kUnsupported);
  EXPECT_NE(built.error().message.find("build failed on"), std::string::npos);
  EXPECT_NE(built.error().message.find("undeclared_name"), std::string::npos)
      << built.error().message;
}

TEST_F(ClDevice, CorruptCachedBinaryIsRebuiltAndReplaced) {
  TempDir dir;
  auto first = build(kAddOneSource, dir.path().string());
  ASSERT_TRUE(first) << first.error().message;
  ASSERT_FALSE(first->cache_path.empty());
  {
    std::ofstream out(first->cache_path, std::ios::binary | std::ios::trunc);
    out << "this is not a program binary";
  }

  auto rebuilt = build(kAddOneSource, dir.path().string());
  ASSERT_TRUE(rebuilt) << rebuilt.error().message;
  EXPECT_FALSE(rebuilt->from_cache);
  EXPECT_NE(rebuilt->warning.find("rebuilt from source"), std::string::npos) << rebuilt->warning;
  EXPECT_EQ(runAddOne(rebuilt->program), (std::vector<cl_int>{2, 3, 4, 5}));

  auto again = build(kAddOneSource, dir.path().string());
  ASSERT_TRUE(again) << again.error().message;
  EXPECT_TRUE(again->from_cache);
}

TEST_F(ClDevice, UnusableCacheDirectoryOnlyWarns) {
  TempDir dir;
  { std::ofstream(dir.file("plain_file")) << "x"; }
  auto built = build(kAddOneSource, dir.file("plain_file") + "/cache");
  ASSERT_TRUE(built) << built.error().message;
  EXPECT_FALSE(built->from_cache);
  EXPECT_TRUE(built->cache_path.empty());
  EXPECT_NE(built->warning.find("cannot create"), std::string::npos) << built->warning;
}

TEST_F(ClDevice, DisabledCacheWritesNothing) {
  TempDir dir;
  ProgramCacheOptions cache;
  cache.directory = dir.path().string();
  cache.enabled = false;
  auto built = buildProgram(ctx_, kAddOneSource, "", cache);
  ASSERT_TRUE(built) << built.error().message;
  EXPECT_TRUE(built->cache_path.empty());
  EXPECT_TRUE(std::filesystem::is_empty(dir.path()));
}

TEST_F(ClDevice, DefaultDirectoryFollowsRaymapCacheDir) {
  TempDir dir;
  const char* old = std::getenv("RAYMAP_CACHE_DIR");
  const std::string saved = old != nullptr ? old : "";
  ::setenv("RAYMAP_CACHE_DIR", dir.path().c_str(), 1);
  auto built = build(kAddOneSource, "");
  if (old != nullptr) {
    ::setenv("RAYMAP_CACHE_DIR", saved.c_str(), 1);
  } else {
    ::unsetenv("RAYMAP_CACHE_DIR");
  }
  ASSERT_TRUE(built) << built.error().message;
  EXPECT_EQ(built->cache_path.rfind((dir.path() / "opencl").string() + "/", 0), 0u)
      << built->cache_path;
}

TEST_F(ClDevice, BufferOverTheDeviceMaximumFails) {
  const auto too_big = static_cast<std::size_t>(ctx_.info.max_alloc_bytes) + 1;
  auto buffer = createBuffer(ctx_, too_big, "voxel slab");
  ASSERT_FALSE(buffer);
  EXPECT_EQ(buffer.error().code, ErrorCode::kCapacity);
  EXPECT_NE(buffer.error().message.find("max"), std::string::npos) << buffer.error().message;
  EXPECT_NE(buffer.error().message.find("voxel slab"), std::string::npos);

  auto small = createBuffer(ctx_, 4096, "small");
  ASSERT_TRUE(small) << small.error().message;
  EXPECT_TRUE(static_cast<bool>(*small));
}

TEST_F(ClDevice, UnknownKernelNameFails) {
  TempDir dir;
  auto built = build(kAddOneSource, dir.path().string());
  ASSERT_TRUE(built) << built.error().message;
  auto kernel = createKernel(built->program, "no_such_kernel");
  ASSERT_FALSE(kernel);
  EXPECT_NE(kernel.error().message.find("no_such_kernel"), std::string::npos);
  EXPECT_TRUE(createKernel(built->program, "add_one"));
}

}  // namespace
}  // namespace raymap::opencl
