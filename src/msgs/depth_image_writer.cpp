// SPDX-License-Identifier: BSD-3-Clause
// CameraInfo and Image written straight into a byte vector: the size is computed first, so the
// vector is resized once (within its capacity once warm) and filled through a cursor.
#include "src/msgs/depth_image_writer.hpp"

#include <bit>
#include <cmath>
#include <cstring>

#include "raymap/assert.hpp"

#include "src/core/byte_order.hpp"

namespace raymap::msgs {
namespace {

/// CDR_LE: the encapsulation header of little-endian XCDR1 (representation 00 01, options 0).
constexpr std::byte kCdrLeHeader[4] = {std::byte{0x00}, std::byte{0x01}, std::byte{0x00},
                                       std::byte{0x00}};
constexpr std::size_t kHeaderBytes = sizeof(kCdrLeHeader);
constexpr std::size_t kPlumbBobCoefficients = 5;
constexpr double kMillimetresPerMetre = 1000.0;
constexpr double kLargestMillimetres = 65535.0;

/// Positions relative to the first byte after the encapsulation header, as XCDR1 aligns.
class Sizer {
 public:
  void align(std::size_t alignment) noexcept {
    size_ = (size_ + alignment - 1) / alignment * alignment;
  }
  void add(std::size_t alignment, std::size_t bytes) noexcept {
    align(alignment);
    size_ += bytes;
  }
  void string(std::string_view text) noexcept { add(4, 4 + text.size() + 1); }
  std::size_t size() const noexcept { return size_; }

 private:
  std::size_t size_ = 0;
};

/// Writes little-endian primitives (CDR_LE) into bytes sized by a Sizer that took the same steps.
class Cursor {
 public:
  explicit Cursor(std::byte* payload) noexcept : payload_(payload) {}
  void align(std::size_t alignment) noexcept {
    const std::size_t aligned = (at_ + alignment - 1) / alignment * alignment;
    std::memset(payload_ + at_, 0, aligned - at_);
    at_ = aligned;
  }
  template <ByteValue T>
  void put(T value) noexcept {
    align(sizeof(T));
    storeLe(payload_ + at_, value);
    at_ += sizeof(T);
  }
  void string(std::string_view text) noexcept {
    put(static_cast<std::uint32_t>(text.size() + 1));
    if (!text.empty()) {
      std::memcpy(payload_ + at_, text.data(), text.size());
    }
    at_ += text.size();
    payload_[at_++] = std::byte{0};
  }
  std::byte* raw(std::size_t bytes) noexcept {
    std::byte* p = payload_ + at_;
    at_ += bytes;
    return p;
  }
  std::size_t position() const noexcept { return at_; }

 private:
  std::byte* payload_;
  std::size_t at_ = 0;
};

/// std_msgs/Header: builtin_interfaces/Time (floor division: 0 <= nanosec < 1e9) and frame_id.
void putHeader(Cursor& cursor, std::int64_t stamp_ns, std::string_view frame_id) noexcept {
  constexpr std::int64_t kNsPerS = 1'000'000'000;
  std::int64_t sec = stamp_ns / kNsPerS;
  std::int64_t nanosec = stamp_ns % kNsPerS;
  if (nanosec < 0) {
    nanosec += kNsPerS;
    sec -= 1;
  }
  cursor.put(static_cast<std::int32_t>(sec));
  cursor.put(static_cast<std::uint32_t>(nanosec));
  cursor.string(frame_id);
}

std::byte* startMessage(std::vector<std::byte>& out, std::size_t payload_bytes) {
  out.resize(kHeaderBytes + payload_bytes);
  std::memcpy(out.data(), kCdrLeHeader, kHeaderBytes);
  return out.data() + kHeaderBytes;
}

std::uint16_t millimetresOf(float depth_m) noexcept {
  // NaN fails the comparison; +inf saturates below, which would turn "no return" into a far
  // return: infinities are "no data" too.
  if (!(depth_m > 0.0f) || std::isinf(depth_m)) {
    return 0;
  }
  const double mm = std::nearbyint(static_cast<double>(depth_m) * kMillimetresPerMetre);
  return static_cast<std::uint16_t>(mm >= kLargestMillimetres ? kLargestMillimetres : mm);
}

}  // namespace

const char* toString(DepthEncoding encoding) noexcept {
  switch (encoding) {
    case DepthEncoding::k16UC1:
      return "16UC1";
    case DepthEncoding::k32FC1:
      return "32FC1";
  }
  return "unknown";
}

void serializeCameraInfo(std::int64_t stamp_ns, std::string_view frame_id,
                         const CameraIntrinsics& camera, std::vector<std::byte>& out) {
  const bool distorted = camera.distortion == DistortionModel::kPlumbBob;
  const std::string_view model = distorted ? "plumb_bob" : "";
  const std::size_t d_count = distorted ? kPlumbBobCoefficients : 0;

  Sizer size;
  size.add(4, 8);  // stamp
  size.string(frame_id);
  size.add(4, 8);  // height, width
  size.string(model);
  size.add(4, 4);
  if (d_count > 0) {
    size.add(8, 8 * d_count);
  }
  size.add(8, 8 * (9 + 9 + 12));  // K, R, P
  size.add(4, 4 * 6);             // binning_x, binning_y, roi offsets and size
  size.add(1, 1);                 // roi.do_rectify

  Cursor cursor(startMessage(out, size.size()));
  putHeader(cursor, stamp_ns, frame_id);
  cursor.put(camera.height);
  cursor.put(camera.width);
  cursor.string(model);
  cursor.put(static_cast<std::uint32_t>(d_count));
  if (distorted) {
    for (const double d : {camera.k1, camera.k2, camera.p1, camera.p2, camera.k3}) {
      cursor.put(d);
    }
  }
  const double k[9] = {camera.fx, 0.0, camera.cx, 0.0, camera.fy, camera.cy, 0.0, 0.0, 1.0};
  const double r[9] = {1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0};
  const double p[12] = {camera.fx, 0.0, camera.cx, 0.0, 0.0, camera.fy,
                        camera.cy, 0.0, 0.0,       0.0, 1.0, 0.0};
  for (const double v : k) {
    cursor.put(v);
  }
  for (const double v : r) {
    cursor.put(v);
  }
  for (const double v : p) {
    cursor.put(v);
  }
  for (int i = 0; i < 6; ++i) {
    cursor.put(std::uint32_t{0});  // binning 0 (= 1), ROI all zero (= the whole image)
  }
  cursor.put(std::uint8_t{0});  // do_rectify
  RAYMAP_ENSURES(cursor.position() + kHeaderBytes == out.size());
}

void serializeDepthImage(std::int64_t stamp_ns, std::string_view frame_id, std::uint32_t width,
                         std::uint32_t height, DepthEncoding encoding, bool big_endian,
                         std::span<const float> depth_m, std::vector<std::byte>& out) {
  const std::size_t pixels = std::size_t{width} * height;
  RAYMAP_EXPECTS(depth_m.size() == pixels);
  const bool millimetres = encoding == DepthEncoding::k16UC1;
  const std::size_t pixel_bytes = millimetres ? 2 : 4;
  const std::size_t data_bytes = pixels * pixel_bytes;
  const std::string_view name = toString(encoding);

  Sizer size;
  size.add(4, 8);
  size.string(frame_id);
  size.add(4, 8);  // height, width
  size.string(name);
  size.add(1, 1);  // is_bigendian
  size.add(4, 4);  // step
  size.add(4, 4 + data_bytes);

  Cursor cursor(startMessage(out, size.size()));
  putHeader(cursor, stamp_ns, frame_id);
  cursor.put(height);
  cursor.put(width);
  cursor.string(name);
  cursor.put(static_cast<std::uint8_t>(big_endian ? 1 : 0));
  cursor.put(static_cast<std::uint32_t>(width * pixel_bytes));
  cursor.put(static_cast<std::uint32_t>(data_bytes));
  std::byte* data = cursor.raw(data_bytes);
  const std::endian order = big_endian ? std::endian::big : std::endian::little;
  for (std::size_t i = 0; i < pixels; ++i) {
    if (millimetres) {
      storeEndian(data + 2 * i, millimetresOf(depth_m[i]), order);
    } else {
      storeEndian(data + 4 * i, depth_m[i], order);
    }
  }
  RAYMAP_ENSURES(cursor.position() + kHeaderBytes == out.size());
}

}  // namespace raymap::msgs
