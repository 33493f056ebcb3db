// SPDX-License-Identifier: BSD-3-Clause
// CameraInfo and Image written straight into a byte vector (src/msgs/cdr_le_writer.hpp: sized
// first, resized once, filled through a cursor).
#include "src/msgs/depth_image_writer.hpp"

#include <bit>
#include <cmath>
#include <cstring>

#include "raymap/assert.hpp"

#include "src/core/byte_order.hpp"
#include "src/msgs/cdr_le_writer.hpp"

namespace raymap::msgs {
namespace {

constexpr std::size_t kHeaderBytes = sizeof(kCdrLeHeader);
constexpr std::size_t kPlumbBobCoefficients = 5;
constexpr double kMillimetresPerMetre = 1000.0;
constexpr double kLargestMillimetres = 65535.0;

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

  CdrSizer size;
  addStdHeader(size, frame_id);
  size.add(4, 8);  // height, width
  size.string(model);
  size.add(4, 4);
  if (d_count > 0) {
    size.add(8, 8 * d_count);
  }
  size.add(8, 8 * (9 + 9 + 12));  // K, R, P
  size.add(4, 4 * 6);             // binning_x, binning_y, roi offsets and size
  size.add(1, 1);                 // roi.do_rectify

  CdrCursor cursor(startCdrLeMessage(out, size.size()));
  putStdHeader(cursor, stamp_ns, frame_id);
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

  CdrSizer size;
  addStdHeader(size, frame_id);
  size.add(4, 8);  // height, width
  size.string(name);
  size.add(1, 1);  // is_bigendian
  size.add(4, 4);  // step
  size.add(4, 4 + data_bytes);

  CdrCursor cursor(startCdrLeMessage(out, size.size()));
  putStdHeader(cursor, stamp_ns, frame_id);
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
