// SPDX-License-Identifier: BSD-3-Clause
// decodePointCloud2 on hand-built CDR: layouts real drivers send, and every malformed input
// giving its own error without reading out of bounds.
#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "src/msgs/point_cloud.hpp"
#include "tests/support/alloc_counter.hpp"
#include "tests/unit/dds/cdr_test_writer.hpp"

namespace raymap::dds {

using namespace msgs;  // the ROS 2 message codecs (src/msgs) these tests exercise
namespace {

using test::encodeCloud;
using test::makeXyzCloud;
using test::mutateForFuzzing;
using test::putValue;
using test::TestCloud;

constexpr std::uint8_t kInt8 = 1;
constexpr std::uint8_t kUInt8 = 2;
constexpr std::uint8_t kUInt16 = 4;
constexpr std::uint8_t kUInt32 = 6;
constexpr std::uint8_t kFloat32 = 7;
constexpr std::uint8_t kFloat64 = 8;

/// Decodes into a vector sized `capacity`, from an exactly sized heap copy of the bytes (so
/// that ASan sees any read past the end).
Expected<CloudHeader, CloudError> decode(const std::vector<std::byte>& bytes,
                                         std::vector<ScanPoint>& out,
                                         const CloudDecodeOptions& options = {}) {
  const std::vector<std::byte> exact(bytes.begin(), bytes.end());
  return decodePointCloud2(std::span<const std::byte>(exact.data(), exact.size()), out, options);
}

CloudError errorOf(const TestCloud& cloud, std::size_t capacity = 64) {
  std::vector<ScanPoint> out(capacity);
  auto result = decode(encodeCloud(cloud), out);
  EXPECT_FALSE(result.has_value());
  return result.has_value() ? CloudError::kMalformed : result.error();
}

/// An Ouster-like 48-byte point: x y z @0/4/8 (+4 pad), intensity f32 @16, t u32 @20,
/// reflectivity u16 @24, ring u16 @26, ambient u16 @28, range u32 @32, 12 bytes of padding.
TestCloud makeOusterCloud(std::uint32_t width, std::uint32_t height, bool big_endian) {
  TestCloud cloud;
  cloud.width = width;
  cloud.height = height;
  cloud.is_bigendian = big_endian;
  cloud.fields = {
      {"x", 0, kFloat32},          {"y", 4, kFloat32},       {"z", 8, kFloat32},
      {"intensity", 16, kFloat32}, {"t", 20, kUInt32},       {"reflectivity", 24, kUInt16},
      {"ring", 26, kUInt16},       {"ambient", 28, kUInt16}, {"range", 32, kUInt32}};
  cloud.point_step = 48;
  cloud.row_step = width * 48;
  cloud.data.assign(std::size_t{cloud.row_step} * height, 0xAB);  // padding is garbage
  for (std::uint32_t r = 0; r < height; ++r) {
    for (std::uint32_t c = 0; c < width; ++c) {
      const std::size_t i = std::size_t{r} * width + c;
      const std::size_t base = i * 48;
      putValue(cloud.data, base + 0, kFloat32, 1.0 + static_cast<double>(i), big_endian);
      putValue(cloud.data, base + 4, kFloat32, -2.0 - static_cast<double>(i), big_endian);
      putValue(cloud.data, base + 8, kFloat32, 0.5, big_endian);
      putValue(cloud.data, base + 16, kFloat32, 10.0 * static_cast<double>(i), big_endian);
      putValue(cloud.data, base + 20, kUInt32, 1000.0 * static_cast<double>(i), big_endian);
      putValue(cloud.data, base + 24, kUInt16, 7, big_endian);
      putValue(cloud.data, base + 26, kUInt16, static_cast<double>(r), big_endian);
      putValue(cloud.data, base + 28, kUInt16, 9, big_endian);
      putValue(cloud.data, base + 32, kUInt32, 1234, big_endian);
    }
  }
  return cloud;
}

TEST(DecodePointCloud2, Float32XyzWithHeader) {
  const TestCloud cloud = makeXyzCloud({1.0F, 2.0F, 3.0F, -4.0F, 5.5F, 6.25F, 7.0F, 8.0F, 9.0F});
  std::vector<ScanPoint> out(8);

  auto result = decode(encodeCloud(cloud), out);

  ASSERT_TRUE(result.has_value());
  const CloudHeader& h = *result;
  EXPECT_EQ(h.stamp_ns, 1'700'000'000LL * 1'000'000'000LL + 250'000'000LL);
  EXPECT_STREQ(h.frame_id, "lidar");
  EXPECT_EQ(h.width, 3U);
  EXPECT_EQ(h.height, 1U);
  EXPECT_EQ(h.points, 3U);
  EXPECT_EQ(h.no_return, 0U);
  EXPECT_FALSE(h.has_time);
  EXPECT_FALSE(h.has_intensity);
  EXPECT_EQ(out[1].x, -4.0F);
  EXPECT_EQ(out[1].y, 5.5F);
  EXPECT_EQ(out[1].z, 6.25F);
  EXPECT_EQ(out[2].x, 7.0F);
  EXPECT_EQ(out[2].time_s, 0.0F);
  EXPECT_EQ(out[2].intensity, 0.0F);
  EXPECT_EQ(out[2].flags, 0U);
}

// Found by fuzz_cdr_point_cloud (tests/fuzz/regressions/cdr_point_cloud): width 0 with a height
// of 2^32 - 1 is an empty cloud, decoded at once (it spun through 4 billion empty rows).
TEST(DecodePointCloud2, ZeroWidthWithAHugeHeightIsAnEmptyCloud) {
  TestCloud cloud = makeXyzCloud({});
  cloud.width = 0;
  cloud.height = 0xFFFFFFFFU;
  cloud.row_step = 16;
  std::vector<ScanPoint> out(8);

  auto result = decode(encodeCloud(cloud), out);

  ASSERT_TRUE(result.has_value());
  EXPECT_EQ(result->points, 0U);
  EXPECT_EQ(result->width, 0U);
  EXPECT_EQ(result->height, 0xFFFFFFFFU);
}

TEST(DecodePointCloud2, Float64Xyz) {
  TestCloud cloud;
  cloud.width = 2;
  cloud.fields = {{"x", 0, kFloat64}, {"y", 8, kFloat64}, {"z", 16, kFloat64}};
  cloud.point_step = 24;
  cloud.row_step = 48;
  cloud.data.assign(48, 0);
  for (std::size_t i = 0; i < 6; ++i) {
    putValue(cloud.data, i * 8, kFloat64, 0.25 * static_cast<double>(i + 1), false);
  }
  std::vector<ScanPoint> out(2);

  auto result = decode(encodeCloud(cloud), out);

  ASSERT_TRUE(result.has_value());
  EXPECT_EQ(result->points, 2U);
  EXPECT_EQ(out[0].x, 0.25F);
  EXPECT_EQ(out[1].z, 1.5F);
}

TEST(DecodePointCloud2, OusterLikeExtraFieldsAndPadding) {
  std::vector<ScanPoint> out(16);

  auto result = decode(encodeCloud(makeOusterCloud(4, 1, false)), out);

  ASSERT_TRUE(result.has_value());
  EXPECT_TRUE(result->has_time);
  EXPECT_TRUE(result->has_intensity);
  for (std::size_t i = 0; i < 4; ++i) {
    const float k = static_cast<float>(i);
    EXPECT_EQ(out[i].x, 1.0F + k);
    EXPECT_EQ(out[i].y, -2.0F - k);
    EXPECT_EQ(out[i].z, 0.5F);
    EXPECT_EQ(out[i].intensity, 10.0F * k);
    EXPECT_NEAR(out[i].time_s, 1e-6 * static_cast<double>(i), 1e-12);
  }
}

TEST(DecodePointCloud2, BigEndianPointDataAndBigEndianCdr) {
  const TestCloud cloud = makeOusterCloud(3, 2, /*big_endian=*/true);
  for (const bool cdr_little : {true, false}) {
    std::vector<ScanPoint> out(6);

    auto result = decode(encodeCloud(cloud, cdr_little), out);

    ASSERT_TRUE(result.has_value()) << "cdr little endian " << cdr_little;
    EXPECT_EQ(result->stamp_ns, 1'700'000'000LL * 1'000'000'000LL + 250'000'000LL);
    EXPECT_EQ(result->points, 6U);
    EXPECT_EQ(out[5].x, 6.0F);
    EXPECT_EQ(out[5].y, -7.0F);
    EXPECT_EQ(out[5].intensity, 50.0F);
    EXPECT_NEAR(out[5].time_s, 5e-6, 1e-12);
  }
}

TEST(DecodePointCloud2, OrganisedCloudSkipsRowPadding) {
  TestCloud cloud;
  cloud.width = 3;
  cloud.height = 2;
  cloud.fields = {{"x", 0, kFloat32}, {"y", 4, kFloat32}, {"z", 8, kFloat32}};
  cloud.point_step = 12;
  cloud.row_step = 3 * 12 + 8;                               // 8 bytes of row padding
  cloud.data.assign(std::size_t{cloud.row_step} * 2, 0xFF);  // padding = NaN patterns
  for (std::size_t r = 0; r < 2; ++r) {
    for (std::size_t c = 0; c < 3; ++c) {
      const std::size_t base = r * cloud.row_step + c * 12;
      putValue(cloud.data, base, kFloat32, static_cast<double>(10 * r + c), false);
      putValue(cloud.data, base + 4, kFloat32, 1.0, false);
      putValue(cloud.data, base + 8, kFloat32, 2.0, false);
    }
  }
  std::vector<ScanPoint> out(6);

  auto result = decode(encodeCloud(cloud), out);

  ASSERT_TRUE(result.has_value());
  EXPECT_EQ(result->width, 3U);
  EXPECT_EQ(result->height, 2U);
  EXPECT_EQ(result->no_return, 0U);
  const float expected_x[6] = {0, 1, 2, 10, 11, 12};
  for (std::size_t i = 0; i < 6; ++i) {
    EXPECT_EQ(out[i].x, expected_x[i]) << i;
    EXPECT_EQ(out[i].flags, 0U);
  }
}

TEST(DecodePointCloud2, NanAndOriginPointsAreNoReturn) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const TestCloud cloud =
      makeXyzCloud({1.0F, 1.0F, 1.0F, nan, nan, nan, 0.0F, 0.0F, 0.0F, 2.0F, nan, 2.0F});
  std::vector<ScanPoint> out(4);

  auto with_origin = decode(encodeCloud(cloud), out);
  ASSERT_TRUE(with_origin.has_value());
  EXPECT_EQ(with_origin->points, 4U);
  EXPECT_EQ(with_origin->no_return, 3U);
  EXPECT_EQ(out[0].flags, 0U);
  EXPECT_EQ(out[1].flags, kPointNoReturn);
  EXPECT_EQ(out[2].flags, kPointNoReturn);
  EXPECT_EQ(out[3].flags, kPointNoReturn);

  CloudDecodeOptions keep_origin;
  keep_origin.origin_is_no_return = false;
  auto without_origin = decode(encodeCloud(cloud), out, keep_origin);
  ASSERT_TRUE(without_origin.has_value());
  EXPECT_EQ(without_origin->no_return, 2U);
  EXPECT_EQ(out[2].flags, 0U);
}

/// A one-point cloud with one extra field `name` of `datatype` holding `value`.
TestCloud cloudWithField(const char* name, std::uint8_t datatype, double value) {
  TestCloud cloud = makeXyzCloud({1.0F, 2.0F, 3.0F});
  cloud.point_step = 24;
  cloud.row_step = 24;
  cloud.data.resize(24, 0);
  cloud.fields.push_back({name, 16, datatype});
  putValue(cloud.data, 16, datatype, value, false);
  return cloud;
}

TEST(DecodePointCloud2, AutoTimeFieldConventions) {
  std::vector<ScanPoint> out(1);
  const double stamp_s = 1'700'000'000.25;

  auto ouster = decode(encodeCloud(cloudWithField("t", kUInt32, 2'500'000)), out);
  ASSERT_TRUE(ouster.has_value());
  EXPECT_TRUE(ouster->has_time);
  EXPECT_NEAR(out[0].time_s, 0.0025, 1e-9);

  auto velodyne = decode(encodeCloud(cloudWithField("time", kFloat32, -0.05)), out);
  ASSERT_TRUE(velodyne.has_value());
  EXPECT_NEAR(out[0].time_s, -0.05, 1e-7);

  auto hesai = decode(encodeCloud(cloudWithField("timestamp", kFloat64, stamp_s + 0.03)), out);
  ASSERT_TRUE(hesai.has_value());
  EXPECT_NEAR(out[0].time_s, 0.03, 1e-6);

  auto robosense = decode(encodeCloud(cloudWithField("time_stamp", kFloat64, stamp_s + 0.07)), out);
  ASSERT_TRUE(robosense.has_value());
  EXPECT_NEAR(out[0].time_s, 0.07, 1e-6);

  auto none = decode(encodeCloud(cloudWithField("noise", kFloat32, 4.0)), out);
  ASSERT_TRUE(none.has_value());
  EXPECT_FALSE(none->has_time);
  EXPECT_EQ(out[0].time_s, 0.0F);
}

TEST(DecodePointCloud2, AutoTimePrefersTOverTime) {
  TestCloud cloud = cloudWithField("time", kFloat32, 0.5);
  cloud.point_step = 28;
  cloud.row_step = 28;
  cloud.data.resize(28, 0);
  cloud.fields.push_back({"t", 20, kUInt32});
  putValue(cloud.data, 20, kUInt32, 1000, false);
  std::vector<ScanPoint> out(1);

  auto result = decode(encodeCloud(cloud), out);

  ASSERT_TRUE(result.has_value());
  EXPECT_NEAR(out[0].time_s, 1e-6, 1e-12);
}

TEST(DecodePointCloud2, ExplicitTimeFieldAndUnit) {
  std::vector<ScanPoint> out(1);
  CloudDecodeOptions livox;
  livox.time_field = "offset_time";
  livox.time_unit = TimeUnit::kRelativeNanoseconds;

  auto found = decode(encodeCloud(cloudWithField("offset_time", kUInt32, 40'000)), out, livox);
  ASSERT_TRUE(found.has_value());
  EXPECT_NEAR(out[0].time_s, 4e-5, 1e-10);

  auto missing = decode(encodeCloud(cloudWithField("t", kUInt32, 40'000)), out, livox);
  ASSERT_FALSE(missing.has_value());
  EXPECT_EQ(missing.error(), CloudError::kMissingTimeField);
}

TEST(DecodePointCloud2, IgnoredTimePutsEveryPointAtTheStampWhateverFieldsTheCloudHas) {
  // sensors[].time_field: none (a field named "none" would reject every cloud).
  std::vector<ScanPoint> out(1);
  CloudDecodeOptions none;
  none.ignore_time = true;
  none.time_field = "none";  // even with a name set: ignore_time wins

  auto with_t = decode(encodeCloud(cloudWithField("t", kUInt32, 40'000)), out, none);
  ASSERT_TRUE(with_t.has_value());
  EXPECT_EQ(out[0].time_s, 0.0f);
  EXPECT_FALSE(with_t.value().has_time);

  auto without = decode(encodeCloud(cloudWithField("intensity", kUInt8, 7)), out, none);
  ASSERT_TRUE(without.has_value());
  EXPECT_EQ(out[0].time_s, 0.0f);
}

TEST(DecodePointCloud2, IntensityOfAnyNumericType) {
  std::vector<ScanPoint> out(1);

  auto result = decode(encodeCloud(cloudWithField("intensity", kUInt8, 200)), out);

  ASSERT_TRUE(result.has_value());
  EXPECT_TRUE(result->has_intensity);
  EXPECT_EQ(out[0].intensity, 200.0F);
}

TEST(DecodePointCloud2, EmptyCloudIsValid) {
  TestCloud cloud = makeXyzCloud({});
  std::vector<ScanPoint> out(1);

  auto result = decode(encodeCloud(cloud), out);

  ASSERT_TRUE(result.has_value());
  EXPECT_EQ(result->points, 0U);
}

// ---- malformed clouds: each its own error ----

TEST(DecodePointCloud2Malformed, XyzTypeAndCount) {
  TestCloud int8_x = makeXyzCloud({1, 2, 3});
  int8_x.fields[0].datatype = kInt8;
  EXPECT_EQ(errorOf(int8_x), CloudError::kBadFieldType);

  TestCloud count2 = makeXyzCloud({1, 2, 3});
  count2.fields[1].count = 2;
  EXPECT_EQ(errorOf(count2), CloudError::kBadFieldType);

  TestCloud unknown_type = makeXyzCloud({1, 2, 3});
  unknown_type.fields[2].datatype = 9;
  EXPECT_EQ(errorOf(unknown_type), CloudError::kBadFieldType);

  TestCloud bad_time = cloudWithField("t", 0, 0);
  EXPECT_EQ(errorOf(bad_time), CloudError::kBadFieldType);

  TestCloud missing_z = makeXyzCloud({1, 2, 3});
  missing_z.fields.pop_back();
  EXPECT_EQ(errorOf(missing_z), CloudError::kMissingXyz);
}

TEST(DecodePointCloud2Malformed, PointStepAndFieldOffsets) {
  TestCloud small_step = makeXyzCloud({1, 2, 3});
  small_step.point_step = 8;
  small_step.row_step = 8;
  small_step.data.resize(8);
  EXPECT_EQ(errorOf(small_step), CloudError::kPointStepTooSmall);

  TestCloud zero_step = makeXyzCloud({1, 2, 3});
  zero_step.point_step = 0;
  EXPECT_EQ(errorOf(zero_step), CloudError::kPointStepTooSmall);

  TestCloud z_outside = makeXyzCloud({1, 2, 3});
  z_outside.fields[2].offset = 14;  // 14 + 4 > 16
  EXPECT_EQ(errorOf(z_outside), CloudError::kFieldOutsidePoint);

  TestCloud huge_offset = makeXyzCloud({1, 2, 3});
  huge_offset.fields[0].offset = 0xFFFFFFFEU;  // no 32-bit wrap-around
  EXPECT_EQ(errorOf(huge_offset), CloudError::kFieldOutsidePoint);

  TestCloud time_outside = cloudWithField("t", kUInt32, 1);
  time_outside.fields.back().offset = 22;
  EXPECT_EQ(errorOf(time_outside), CloudError::kFieldOutsidePoint);
}

TEST(DecodePointCloud2Malformed, DataSizeAndRowStep) {
  TestCloud short_data = makeXyzCloud({1, 2, 3, 4, 5, 6});
  short_data.data.pop_back();
  EXPECT_EQ(errorOf(short_data), CloudError::kDataSizeMismatch);

  TestCloud long_data = makeXyzCloud({1, 2, 3, 4, 5, 6});
  long_data.data.push_back(0);
  EXPECT_EQ(errorOf(long_data), CloudError::kDataSizeMismatch);

  TestCloud wrong_width = makeXyzCloud({1, 2, 3, 4, 5, 6});
  wrong_width.width = 3;  // row_step still 32
  EXPECT_EQ(errorOf(wrong_width), CloudError::kRowStepTooSmall);

  TestCloud wrong_height = makeXyzCloud({1, 2, 3, 4, 5, 6});
  wrong_height.height = 2;
  EXPECT_EQ(errorOf(wrong_height), CloudError::kDataSizeMismatch);
}

TEST(DecodePointCloud2Malformed, AbsurdDimensions) {
  TestCloud wide = makeXyzCloud({1, 2, 3});
  wide.width = 1U << 31;
  EXPECT_EQ(errorOf(wide), CloudError::kRowStepTooSmall);

  TestCloud both = makeXyzCloud({1, 2, 3});
  both.width = 1U << 31;
  both.height = 1U << 31;
  both.row_step = 0xFFFFFFFFU;
  EXPECT_EQ(errorOf(both), CloudError::kRowStepTooSmall);

  TestCloud tall = makeXyzCloud({1, 2, 3});
  tall.height = 1U << 31;
  EXPECT_EQ(errorOf(tall), CloudError::kDataSizeMismatch);

  // A consistent cloud bigger than the caller's buffer is dropped whole.
  TestCloud big = makeXyzCloud(std::vector<float>(3 * 10, 1.0F));
  EXPECT_EQ(errorOf(big, 9), CloudError::kTooManyPoints);
}

/// Overwrites 4 bytes (little endian) at `at` of an encoded message.
void patchU32(std::vector<std::byte>& bytes, std::size_t at, std::uint32_t value) {
  for (std::size_t k = 0; k < 4; ++k) {
    bytes[at + k] = static_cast<std::byte>((value >> (8 * k)) & 0xFFU);
  }
}

TEST(DecodePointCloud2Malformed, AbsurdSequenceAndStringLengths) {
  const TestCloud cloud = makeXyzCloud({1, 2, 3});
  std::vector<ScanPoint> out(4);
  // Payload layout: sec @0, nanosec @4, frame_id length @8 ("lidar" + NUL: 6 bytes) ->
  // height @20, width @24, fields count @28 (+4 for the encapsulation header).
  std::vector<std::byte> fields = encodeCloud(cloud);
  patchU32(fields, 4 + 28, 0xFFFFFFFFU);
  auto huge_fields = decode(fields, out);
  ASSERT_FALSE(huge_fields.has_value());
  EXPECT_EQ(huge_fields.error(), CloudError::kTruncated);

  std::vector<std::byte> data = encodeCloud(cloud);
  const std::size_t data_length_at = data.size() - 1 - cloud.data.size() - 4;
  patchU32(data, data_length_at, 0xFFFFFFF0U);
  auto huge_data = decode(data, out);
  ASSERT_FALSE(huge_data.has_value());
  EXPECT_EQ(huge_data.error(), CloudError::kTruncated);

  std::vector<std::byte> frame = encodeCloud(cloud);
  patchU32(frame, 4 + 8, 0x7FFFFFFFU);
  auto huge_frame = decode(frame, out);
  ASSERT_FALSE(huge_frame.has_value());
  EXPECT_EQ(huge_frame.error(), CloudError::kTruncated);

  std::vector<std::byte> no_nul = encodeCloud(cloud);
  no_nul[4 + 12 + 5] = std::byte{'x'};  // "lidar" loses its NUL
  auto malformed = decode(no_nul, out);
  ASSERT_FALSE(malformed.has_value());
  EXPECT_EQ(malformed.error(), CloudError::kMalformed);
}

TEST(DecodePointCloud2Malformed, FrameIdLength) {
  TestCloud longest = makeXyzCloud({1, 2, 3});
  longest.frame_id = std::string(63, 'f');
  std::vector<ScanPoint> out(1);
  auto ok = decode(encodeCloud(longest), out);
  ASSERT_TRUE(ok.has_value());
  EXPECT_EQ(std::strlen(ok->frame_id), 63U);

  TestCloud too_long = makeXyzCloud({1, 2, 3});
  too_long.frame_id = std::string(64, 'f');
  EXPECT_EQ(errorOf(too_long), CloudError::kFrameIdTooLong);
}

TEST(DecodePointCloud2Malformed, BadEncapsulationAndEmptyInput) {
  std::vector<ScanPoint> out(1);
  const std::vector<std::byte> good = encodeCloud(makeXyzCloud({1, 2, 3}));
  for (const std::uint8_t kind : {std::uint8_t{2}, std::uint8_t{3}, std::uint8_t{0x11}}) {
    std::vector<std::byte> bad = good;
    bad[1] = std::byte{kind};
    auto result = decode(bad, out);
    ASSERT_FALSE(result.has_value());
    EXPECT_EQ(result.error(), CloudError::kBadEncapsulation);
  }
  std::vector<std::byte> first_byte = good;
  first_byte[0] = std::byte{1};
  auto bad_first = decode(first_byte, out);
  ASSERT_FALSE(bad_first.has_value());
  EXPECT_EQ(bad_first.error(), CloudError::kBadEncapsulation);

  auto empty = decodePointCloud2({}, out, {});
  ASSERT_FALSE(empty.has_value());
  EXPECT_EQ(empty.error(), CloudError::kBadEncapsulation);
}

TEST(DecodePointCloud2Malformed, EveryTruncationIsRefused) {
  const std::vector<std::byte> full = encodeCloud(makeOusterCloud(3, 2, false));
  std::vector<ScanPoint> out(16);
  for (std::size_t size = 0; size < full.size(); ++size) {
    const std::vector<std::byte> cut(full.begin(),
                                     full.begin() + static_cast<std::ptrdiff_t>(size));
    auto result = decode(cut, out);
    ASSERT_FALSE(result.has_value()) << size;
    EXPECT_EQ(result.error(), size < 4 ? CloudError::kBadEncapsulation : CloudError::kTruncated)
        << size;
  }
}

TEST(DecodePointCloud2Fuzz, RandomMutationsNeverCrash) {
  const std::vector<std::byte> valid = encodeCloud(makeOusterCloud(4, 2, false));
  std::mt19937 rng(12345);
  std::vector<ScanPoint> out(64);
  int accepted = 0;
  for (int round = 0; round < 5000; ++round) {
    std::vector<std::byte> bytes = valid;
    mutateForFuzzing(bytes, rng);
    auto result = decode(bytes, out);
    if (result.has_value()) {
      ++accepted;
      ASSERT_LE(result->points, out.size());
      ASSERT_LE(result->no_return, result->points);
      ASSERT_LT(std::strlen(result->frame_id), sizeof(CloudHeader::frame_id));
    }
  }
  // Mutations of point values leave valid clouds: the fuzzing reaches the point loop.
  EXPECT_GT(accepted, 100);
}

TEST(DecodePointCloud2, DoesNotAllocate) {
  if (!raymap::test::allocationCountingAvailable()) {
    GTEST_SKIP() << "allocation counting is off in sanitizer builds";
  }
  const std::vector<std::byte> bytes = encodeCloud(makeOusterCloud(64, 4, false));
  std::vector<ScanPoint> out(256);
  raymap::test::AllocationScope scope;

  auto result = decodePointCloud2(bytes, out, {});

  EXPECT_TRUE(result.has_value());
  EXPECT_EQ(scope.count(), 0U);
}

}  // namespace
}  // namespace raymap::dds
