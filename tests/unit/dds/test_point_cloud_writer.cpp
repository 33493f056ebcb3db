// SPDX-License-Identifier: BSD-3-Clause
// serializeOusterCloud: byte for byte the cloud the tests' own PointCloud2 writer makes of the same
// points (an independent encoder), and back through decodePointCloud2 to the same points.
#include <cmath>
#include <limits>
#include <vector>

#include <gtest/gtest.h>

#include "src/msgs/point_cloud.hpp"
#include "src/msgs/point_cloud_writer.hpp"
#include "src/msgs/ros_time.hpp"
#include "tests/unit/dds/cdr_test_writer.hpp"

namespace raymap::msgs {
namespace {

namespace test = dds::test;

constexpr std::uint32_t kRows = 4;
constexpr std::uint32_t kColumns = 50;
constexpr std::int64_t kStampNs = 1'700'000'000'250'000'000;

/// A sweep of kRows x kColumns points, every ninth without a return.
std::vector<ScanPoint> sweep() {
  std::vector<ScanPoint> points;
  for (std::uint32_t r = 0; r < kRows; ++r) {
    for (std::uint32_t c = 0; c < kColumns; ++c) {
      const float a = 0.12f * static_cast<float>(c);
      const float range = 2.0f + 0.37f * static_cast<float>(r) + 0.01f * static_cast<float>(c);
      ScanPoint p{range * std::cos(a),
                  range * std::sin(a),
                  -0.2f + 0.1f * static_cast<float>(r),
                  1e-4f * static_cast<float>(c),
                  5.0f + static_cast<float>(c),
                  0u};
      if ((r * kColumns + c) % 9 == 4) {
        p.flags = kPointNoReturn;
      }
      points.push_back(p);
    }
  }
  return points;
}

TEST(PointCloudWriter, IsTheCloudAnIndependentEncoderMakesOfTheSamePoints) {
  const std::vector<ScanPoint> points = sweep();
  std::vector<std::byte> ours;
  serializeOusterCloud(kStampNs, "os_lidar", kRows, points, {}, ours);

  test::TestCloud cloud;
  cloud.sec = 1'700'000'000;
  cloud.nanosec = 250'000'000;
  cloud.frame_id = "os_lidar";
  cloud.height = kRows;
  cloud.width = kColumns;
  cloud.fields = {{"x", 0, 7},          {"y", 4, 7},        {"z", 8, 7},
                  {"intensity", 16, 7}, {"t", 20, 6},       {"reflectivity", 24, 4},
                  {"ring", 26, 4},      {"ambient", 28, 4}, {"range", 32, 6}};
  cloud.point_step = kOusterPointStep;
  cloud.row_step = kColumns * kOusterPointStep;
  cloud.data.assign(std::size_t{cloud.row_step} * kRows, 0);
  for (std::size_t i = 0; i < points.size(); ++i) {
    const ScanPoint& p = points[i];
    const bool none = (p.flags & kPointNoReturn) != 0u;
    const double x = none ? 0.0 : static_cast<double>(p.x);
    const double y = none ? 0.0 : static_cast<double>(p.y);
    const double z = none ? 0.0 : static_cast<double>(p.z);
    const std::size_t at = i * kOusterPointStep;
    test::putValue(cloud.data, at + 0, 7, x, false);
    test::putValue(cloud.data, at + 4, 7, y, false);
    test::putValue(cloud.data, at + 8, 7, z, false);
    test::putValue(cloud.data, at + 16, 7, static_cast<double>(p.intensity), false);
    test::putValue(cloud.data, at + 20, 6, std::nearbyint(static_cast<double>(p.time_s) * 1e9),
                   false);
    test::putValue(cloud.data, at + 26, 4, static_cast<double>(i / kColumns), false);
    test::putValue(cloud.data, at + 32, 6,
                   std::nearbyint(1000.0 * std::sqrt(x * x + y * y + z * z)), false);
  }
  EXPECT_EQ(ours, test::encodeCloud(cloud));
}

TEST(PointCloudWriter, DecodesBackToTheSamePoints) {
  const std::vector<ScanPoint> points = sweep();
  std::vector<std::uint16_t> rings(points.size());
  for (std::size_t i = 0; i < rings.size(); ++i) {
    rings[i] = static_cast<std::uint16_t>(100 + i % 7);
  }
  std::vector<std::byte> bytes;
  serializeOusterCloud(kStampNs, "os_lidar", kRows, points, rings, bytes);
  std::vector<ScanPoint> back(points.size());
  const auto header = decodePointCloud2(bytes, back, CloudDecodeOptions{});
  ASSERT_TRUE(header.has_value());
  EXPECT_EQ(header->stamp_ns, kStampNs);
  EXPECT_STREQ(header->frame_id, "os_lidar");
  EXPECT_EQ(header->height, kRows);
  EXPECT_EQ(header->width, kColumns);
  EXPECT_EQ(header->points, points.size());
  EXPECT_TRUE(header->has_time);
  EXPECT_TRUE(header->has_intensity);
  std::uint32_t no_return = 0;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const ScanPoint& in = points[i];
    const ScanPoint& out = back[i];
    if ((in.flags & kPointNoReturn) != 0u) {
      ++no_return;
      EXPECT_NE(out.flags & kPointNoReturn, 0u) << i;  // (0, 0, 0): the driver's missing return
      continue;
    }
    EXPECT_EQ(out.flags & kPointNoReturn, 0u) << i;
    EXPECT_EQ(out.x, in.x) << i;
    EXPECT_EQ(out.y, in.y) << i;
    EXPECT_EQ(out.z, in.z) << i;
    EXPECT_EQ(out.intensity, in.intensity) << i;
    EXPECT_NEAR(out.time_s, in.time_s, 1e-9f) << i;  // whole nanoseconds on the wire
  }
  EXPECT_EQ(header->no_return, no_return);
}

TEST(PointCloudWriter, OddTimesAreClampedToTheFieldsRange) {
  std::vector<ScanPoint> points(3, ScanPoint{1.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0u});
  points[0].time_s = -0.5f;
  points[1].time_s = std::numeric_limits<float>::quiet_NaN();
  points[2].time_s = 10.0f;  // beyond uint32 nanoseconds
  std::vector<std::byte> bytes;
  serializeOusterCloud(0, "l", 1, points, {}, bytes);
  std::vector<ScanPoint> back(points.size());
  CloudDecodeOptions options;
  options.time_unit = TimeUnit::kRelativeNanoseconds;
  const auto header = decodePointCloud2(bytes, back, options);
  ASSERT_TRUE(header.has_value());
  EXPECT_EQ(back[0].time_s, 0.0f);
  EXPECT_EQ(back[1].time_s, 0.0f);
  EXPECT_NEAR(back[2].time_s, 4.294967295f, 1e-6f);
}

TEST(RosTime, SplitsStampsAsBuiltinInterfacesTimeBeforeAndAfterTheEpoch) {
  const RosTime after = rosTimeOf(1'700'000'000'250'000'000);
  EXPECT_EQ(after.sec, 1'700'000'000);
  EXPECT_EQ(after.nanosec, 250'000'000u);
  const RosTime before = rosTimeOf(-1'250'000'000);  // 1.25 s before: -2 s + 0.75 s
  EXPECT_EQ(before.sec, -2);
  EXPECT_EQ(before.nanosec, 750'000'000u);
  const RosTime whole = rosTimeOf(-2'000'000'000);
  EXPECT_EQ(whole.sec, -2);
  EXPECT_EQ(whole.nanosec, 0u);
  EXPECT_EQ(nanosecondsOf(static_cast<std::int32_t>(before.sec), before.nanosec), -1'250'000'000);
}

}  // namespace
}  // namespace raymap::msgs
