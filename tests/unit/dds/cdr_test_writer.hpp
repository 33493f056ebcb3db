// SPDX-License-Identifier: BSD-3-Clause
// A small XCDR1 encoder for the DDS tests: hand-built ROS 2 messages (PointCloud2, Odometry,
// TFMessage, Image, CameraInfo), in either byte order, to feed the decoders.
#pragma once

#include <cstddef>
#include <cstdint>
#include <random>
#include <string>
#include <vector>

namespace raymap::dds::test {

/// @brief Writes an encapsulation header and then XCDR1 primitives aligned to their size
/// relative to the byte after the header (ROS 2 / rmw_cyclonedds rules).
class CdrTestWriter {
 public:
  explicit CdrTestWriter(bool little_endian = true);

  void align(std::size_t alignment);
  void u8(std::uint8_t value);
  void boolean(bool value) { u8(value ? 1 : 0); }
  void u16(std::uint16_t value);
  void u32(std::uint32_t value);
  void i32(std::int32_t value);
  void f32(float value);
  void f64(double value);
  /// uint32 length including the NUL, the bytes, the NUL.
  void string(const std::string& value);
  void bytes(const std::vector<std::uint8_t>& value);

  const std::vector<std::byte>& data() const { return data_; }

 private:
  void raw(const void* value, std::size_t size);
  std::vector<std::byte> data_;
  bool little_endian_;
};

/// A PointField as a test writes it.
struct TestField {
  std::string name;
  std::uint32_t offset;
  std::uint8_t datatype;
  std::uint32_t count = 1;
};

/// Every member of a PointCloud2, so that a test can break any of them.
struct TestCloud {
  std::int32_t sec = 1'700'000'000;
  std::uint32_t nanosec = 250'000'000;
  std::string frame_id = "lidar";
  std::uint32_t height = 1;
  std::uint32_t width = 0;
  std::vector<TestField> fields;
  bool is_bigendian = false;
  std::uint32_t point_step = 0;
  std::uint32_t row_step = 0;
  std::vector<std::uint8_t> data;
  bool is_dense = true;
};

/// @brief Serializes a TestCloud as sensor_msgs/PointCloud2.
std::vector<std::byte> encodeCloud(const TestCloud& cloud, bool cdr_little_endian = true);

/// @brief Stores `value` converted to `datatype` (PointField constants) at data[offset], in the
/// given byte order.
void putValue(std::vector<std::uint8_t>& data, std::size_t offset, std::uint8_t datatype,
              double value, bool big_endian);

/// @brief An unorganised cloud of float32 x/y/z (point_step 16, 4 bytes of padding).
TestCloud makeXyzCloud(const std::vector<float>& xyz);

/// A pose as the tests encode it.
struct TestPose {
  std::int32_t sec = 100;
  std::uint32_t nanosec = 5;
  std::string parent = "odom";
  std::string child = "base_link";
  double t[3] = {1.0, 2.0, 3.0};
  double q[4] = {0.0, 0.0, 0.0, 1.0};  ///< x, y, z, w
};

/// @brief Serializes nav_msgs/Odometry (covariances and twist filled with small numbers).
std::vector<std::byte> encodeOdometry(const TestPose& pose, bool cdr_little_endian = true);
/// @brief Serializes tf2_msgs/TFMessage.
std::vector<std::byte> encodeTfMessage(const std::vector<TestPose>& poses,
                                       bool cdr_little_endian = true);

/// Every member of a sensor_msgs/Image, so that a test can break any of them.
struct TestImage {
  std::int32_t sec = 1'700'000'000;
  std::uint32_t nanosec = 125'000'000;
  std::string frame_id = "camera_depth_optical_frame";
  std::uint32_t height = 0;
  std::uint32_t width = 0;
  std::string encoding = "32FC1";
  std::uint8_t is_bigendian = 0;
  std::uint32_t step = 0;
  std::vector<std::uint8_t> data;
};

/// @brief Serializes a TestImage as sensor_msgs/Image.
std::vector<std::byte> encodeImage(const TestImage& image, bool cdr_little_endian = true);

/// @brief A 32FC1 (metres) or 16UC1 (millimetres, rounded) image of row-major depths, with
/// `row_padding` bytes after each row and the pixels in the given byte order.
TestImage makeDepthImage(std::uint32_t width, std::uint32_t height,
                         const std::vector<float>& depth_m, bool millimetres,
                         bool big_endian = false, std::uint32_t row_padding = 0);

/// Every member of a sensor_msgs/CameraInfo.
struct TestCameraInfo {
  std::int32_t sec = 1'700'000'000;
  std::uint32_t nanosec = 125'000'000;
  std::string frame_id = "camera_depth_optical_frame";
  std::uint32_t height = 480;
  std::uint32_t width = 640;
  std::string distortion_model = "plumb_bob";
  std::vector<double> d = {0.0, 0.0, 0.0, 0.0, 0.0};
  double k[9] = {385.0, 0.0, 320.5, 0.0, 385.0, 240.5, 0.0, 0.0, 1.0};
  double r[9] = {1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0};
  double p[12] = {385.0, 0.0, 320.5, 0.0, 0.0, 385.0, 240.5, 0.0, 0.0, 0.0, 1.0, 0.0};
  std::uint32_t binning_x = 0;
  std::uint32_t binning_y = 0;
  std::uint32_t roi_x_offset = 0;
  std::uint32_t roi_y_offset = 0;
  std::uint32_t roi_height = 0;
  std::uint32_t roi_width = 0;
  bool roi_do_rectify = false;
};

/// @brief Serializes a TestCameraInfo as sensor_msgs/CameraInfo.
std::vector<std::byte> encodeCameraInfo(const TestCameraInfo& info, bool cdr_little_endian = true);

/// @brief 1 to 8 random edits of `bytes` for the decoders' fuzz tests: a random byte, 0xFF, a
/// flipped bit, or the message cut short after a random byte.
void mutateForFuzzing(std::vector<std::byte>& bytes, std::mt19937& rng);

}  // namespace raymap::dds::test
