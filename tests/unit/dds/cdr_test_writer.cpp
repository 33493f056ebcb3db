// SPDX-License-Identifier: BSD-3-Clause
// The XCDR1 test encoder (written from the CDR rules, independent of src/dds).
#include "tests/unit/dds/cdr_test_writer.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>

namespace raymap::dds::test {

CdrTestWriter::CdrTestWriter(bool little_endian) : little_endian_(little_endian) {
  data_.push_back(std::byte{0});
  data_.push_back(std::byte{little_endian ? std::uint8_t{1} : std::uint8_t{0}});
  data_.push_back(std::byte{0});
  data_.push_back(std::byte{0});
}

void CdrTestWriter::align(std::size_t alignment) {
  while ((data_.size() - 4) % alignment != 0) {
    data_.push_back(std::byte{0});
  }
}

void CdrTestWriter::raw(const void* value, std::size_t size) {
  align(size);
  std::byte bytes[8];
  std::memcpy(bytes, value, size);
  if (!little_endian_) {
    std::reverse(bytes, bytes + size);
  }
  data_.insert(data_.end(), bytes, bytes + size);
}

void CdrTestWriter::u8(std::uint8_t value) { raw(&value, 1); }
void CdrTestWriter::u16(std::uint16_t value) { raw(&value, 2); }
void CdrTestWriter::u32(std::uint32_t value) { raw(&value, 4); }
void CdrTestWriter::i32(std::int32_t value) { raw(&value, 4); }
void CdrTestWriter::f32(float value) { raw(&value, 4); }
void CdrTestWriter::f64(double value) { raw(&value, 8); }

void CdrTestWriter::string(const std::string& value) {
  u32(static_cast<std::uint32_t>(value.size() + 1));
  for (const char c : value) {
    data_.push_back(static_cast<std::byte>(c));
  }
  data_.push_back(std::byte{0});
}

void CdrTestWriter::bytes(const std::vector<std::uint8_t>& value) {
  u32(static_cast<std::uint32_t>(value.size()));
  for (const std::uint8_t b : value) {
    data_.push_back(std::byte{b});
  }
}

std::vector<std::byte> encodeCloud(const TestCloud& cloud, bool cdr_little_endian) {
  CdrTestWriter w(cdr_little_endian);
  w.i32(cloud.sec);
  w.u32(cloud.nanosec);
  w.string(cloud.frame_id);
  w.u32(cloud.height);
  w.u32(cloud.width);
  w.u32(static_cast<std::uint32_t>(cloud.fields.size()));
  for (const TestField& field : cloud.fields) {
    w.string(field.name);
    w.u32(field.offset);
    w.u8(field.datatype);
    w.u32(field.count);
  }
  w.boolean(cloud.is_bigendian);
  w.u32(cloud.point_step);
  w.u32(cloud.row_step);
  w.bytes(cloud.data);
  w.boolean(cloud.is_dense);
  return w.data();
}

void putValue(std::vector<std::uint8_t>& data, std::size_t offset, std::uint8_t datatype,
              double value, bool big_endian) {
  std::uint8_t bytes[8] = {};
  std::size_t size = 0;
  const auto put = [&](auto typed) {
    size = sizeof(typed);
    std::memcpy(bytes, &typed, size);
  };
  switch (datatype) {
    case 1:
      put(static_cast<std::int8_t>(value));
      break;
    case 2:
      put(static_cast<std::uint8_t>(value));
      break;
    case 3:
      put(static_cast<std::int16_t>(value));
      break;
    case 4:
      put(static_cast<std::uint16_t>(value));
      break;
    case 5:
      put(static_cast<std::int32_t>(value));
      break;
    case 6:
      put(static_cast<std::uint32_t>(value));
      break;
    case 7:
      put(static_cast<float>(value));
      break;
    default:
      put(value);
      break;
  }
  if (big_endian) {
    std::reverse(bytes, bytes + size);
  }
  std::copy(bytes, bytes + size, data.begin() + static_cast<std::ptrdiff_t>(offset));
}

TestCloud makeXyzCloud(const std::vector<float>& xyz) {
  TestCloud cloud;
  const std::size_t n = xyz.size() / 3;
  cloud.width = static_cast<std::uint32_t>(n);
  cloud.fields = {{"x", 0, 7}, {"y", 4, 7}, {"z", 8, 7}};
  cloud.point_step = 16;
  cloud.row_step = cloud.width * cloud.point_step;
  cloud.data.assign(n * 16, 0);
  for (std::size_t i = 0; i < n; ++i) {
    for (std::size_t k = 0; k < 3; ++k) {
      putValue(cloud.data, i * 16 + 4 * k, 7, static_cast<double>(xyz[3 * i + k]), false);
    }
  }
  return cloud;
}

namespace {

void writePoseBody(CdrTestWriter& w, const TestPose& pose) {
  w.f64(pose.t[0]);
  w.f64(pose.t[1]);
  w.f64(pose.t[2]);
  w.f64(pose.q[0]);
  w.f64(pose.q[1]);
  w.f64(pose.q[2]);
  w.f64(pose.q[3]);
}

}  // namespace

std::vector<std::byte> encodeOdometry(const TestPose& pose, bool cdr_little_endian) {
  CdrTestWriter w(cdr_little_endian);
  w.i32(pose.sec);
  w.u32(pose.nanosec);
  w.string(pose.parent);
  w.string(pose.child);
  writePoseBody(w, pose);
  for (int i = 0; i < 36; ++i) {
    w.f64(0.01 * i);  // pose covariance
  }
  for (int i = 0; i < 6; ++i) {
    w.f64(0.5 * i);  // twist
  }
  for (int i = 0; i < 36; ++i) {
    w.f64(0.02 * i);  // twist covariance
  }
  return w.data();
}

std::vector<std::byte> encodeTfMessage(const std::vector<TestPose>& poses, bool cdr_little_endian) {
  CdrTestWriter w(cdr_little_endian);
  w.u32(static_cast<std::uint32_t>(poses.size()));
  for (const TestPose& pose : poses) {
    w.i32(pose.sec);
    w.u32(pose.nanosec);
    w.string(pose.parent);
    w.string(pose.child);
    writePoseBody(w, pose);
  }
  return w.data();
}

std::vector<std::byte> encodeImage(const TestImage& image, bool cdr_little_endian) {
  CdrTestWriter w(cdr_little_endian);
  w.i32(image.sec);
  w.u32(image.nanosec);
  w.string(image.frame_id);
  w.u32(image.height);
  w.u32(image.width);
  w.string(image.encoding);
  w.u8(image.is_bigendian);
  w.u32(image.step);
  w.bytes(image.data);
  return w.data();
}

TestImage makeDepthImage(std::uint32_t width, std::uint32_t height,
                         const std::vector<float>& depth_m, bool millimetres, bool big_endian,
                         std::uint32_t row_padding) {
  TestImage image;
  image.width = width;
  image.height = height;
  image.encoding = millimetres ? "16UC1" : "32FC1";
  image.is_bigendian = big_endian ? 1 : 0;
  const std::uint32_t pixel_bytes = millimetres ? 2 : 4;
  image.step = width * pixel_bytes + row_padding;
  image.data.assign(std::size_t{image.step} * height, 0xAB);  // padding: not zero on purpose
  for (std::uint32_t v = 0; v < height; ++v) {
    for (std::uint32_t u = 0; u < width; ++u) {
      const float d = depth_m[std::size_t{v} * width + u];
      const std::size_t at = std::size_t{v} * image.step + std::size_t{u} * pixel_bytes;
      if (millimetres) {
        const double mm =
            std::isfinite(d) && d > 0.0f ? std::round(static_cast<double>(d) * 1000.0) : 0.0;
        putValue(image.data, at, 4, mm, big_endian);
      } else {
        putValue(image.data, at, 7, static_cast<double>(d), big_endian);
      }
    }
  }
  return image;
}

std::vector<std::byte> encodeCameraInfo(const TestCameraInfo& info, bool cdr_little_endian) {
  CdrTestWriter w(cdr_little_endian);
  w.i32(info.sec);
  w.u32(info.nanosec);
  w.string(info.frame_id);
  w.u32(info.height);
  w.u32(info.width);
  w.string(info.distortion_model);
  w.u32(static_cast<std::uint32_t>(info.d.size()));
  for (const double d : info.d) {
    w.f64(d);
  }
  for (const double v : info.k) {
    w.f64(v);
  }
  for (const double v : info.r) {
    w.f64(v);
  }
  for (const double v : info.p) {
    w.f64(v);
  }
  w.u32(info.binning_x);
  w.u32(info.binning_y);
  w.u32(info.roi_x_offset);
  w.u32(info.roi_y_offset);
  w.u32(info.roi_height);
  w.u32(info.roi_width);
  w.boolean(info.roi_do_rectify);
  return w.data();
}

void mutateForFuzzing(std::vector<std::byte>& bytes, std::mt19937& rng) {
  const int edits = 1 + static_cast<int>(rng() % 8);
  for (int e = 0; e < edits && !bytes.empty(); ++e) {
    const std::size_t at = rng() % bytes.size();
    switch (rng() % 4) {
      case 0:
        bytes[at] = static_cast<std::byte>(rng() & 0xFFU);
        break;
      case 1:
        bytes[at] = std::byte{0xFF};
        break;
      case 2:
        bytes[at] ^= static_cast<std::byte>(1U << (rng() % 8));
        break;
      default:
        bytes.resize(at + 1);
        break;
    }
  }
}

}  // namespace raymap::dds::test
