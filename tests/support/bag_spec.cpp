// SPDX-License-Identifier: BSD-3-Clause
#include "tests/support/bag_spec.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <vector>

namespace raymap::test {
namespace {

/// builtin_interfaces/Time: whole seconds (floor) and the nanoseconds after them.
Json timeJson(std::int64_t ns) {
  const std::int64_t sec = ns >= 0 ? ns / 1000000000 : -((-ns + 999999999) / 1000000000);
  return {{"sec", sec}, {"nanosec", ns - sec * 1000000000}};
}

Json headerJson(std::int64_t stamp_ns, const std::string& frame) {
  return {{"stamp", timeJson(stamp_ns)}, {"frame_id", frame}};
}

Json pointJson(const Eigen::Vector3d& v) { return {{"x", v.x()}, {"y", v.y()}, {"z", v.z()}}; }

Json quaternionJson(const Eigen::Quaterniond& q) {
  return {{"x", q.x()}, {"y", q.y()}, {"z", q.z()}, {"w", q.w()}};
}

template <class T>
void put(std::vector<std::byte>& out, std::size_t at, T value) {
  std::memcpy(out.data() + at, &value, sizeof(T));  // little-endian host (x86, ARM)
}

}  // namespace

BagSpecWriter::BagSpecWriter(const std::string& path) : out_(path) {}

void BagSpecWriter::channel(const std::string& topic, const std::string& type,
                            const std::string& qos) {
  const Json line = {{"op", "channel"}, {"topic", topic}, {"type", type}, {"qos", qos}};
  out_ << line.dump() << "\n";
}

void BagSpecWriter::message(const std::string& topic, std::int64_t log_time_ns,
                            const std::string& body) {
  writeMessage(topic, log_time_ns, Json::parse(body));
}

void BagSpecWriter::writeMessage(const std::string& topic, std::int64_t log_time_ns,
                                 const Json& body) {
  // The times as strings: JavaScript's numbers hold integers exactly only up to 2^53.
  const Json line = {
      {"op", "message"},
      {"topic", topic},
      {"log_time_ns", std::to_string(log_time_ns)},
      {"publish_time_ns", std::to_string(log_time_ns)},
      {"msg", body},
  };
  out_ << line.dump() << "\n";
}

void BagSpecWriter::ousterCloud(const std::string& topic, std::int64_t log_time_ns,
                                std::int64_t stamp_ns, const std::string& frame,
                                std::span<const msgs::ScanPoint> points,
                                std::span<const std::uint16_t> rings) {
  constexpr std::size_t kStep = 48;
  std::vector<std::byte> data(points.size() * kStep, std::byte{0});
  for (std::size_t i = 0; i < points.size(); ++i) {
    const msgs::ScanPoint& p = points[i];
    const bool none = !std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z);
    const std::size_t at = i * kStep;
    put(data, at + 0, none ? 0.0f : p.x);
    put(data, at + 4, none ? 0.0f : p.y);
    put(data, at + 8, none ? 0.0f : p.z);
    put(data, at + 16, p.intensity);
    put(data, at + 20, static_cast<std::uint32_t>(std::llround(double(p.time_s) * 1e9)));
    put(data, at + 26, i < rings.size() ? rings[i] : std::uint16_t{0});
  }
  const auto field = [](const char* name, int offset, int datatype) {
    return Json{{"name", name}, {"offset", offset}, {"datatype", datatype}, {"count", 1}};
  };
  writeMessage(topic, log_time_ns,
               Json{
                   {"header", headerJson(stamp_ns, frame)},
                   {"height", 1},
                   {"width", points.size()},
                   {"fields",
                    {field("x", 0, 7), field("y", 4, 7), field("z", 8, 7),
                     field("intensity", 16, 7), field("t", 20, 6), field("ring", 26, 4)}},
                   {"is_bigendian", false},
                   {"point_step", kStep},
                   {"row_step", data.size()},
                   {"data", {{"base64", base64(data)}}},
                   {"is_dense", true},
               });
}

void BagSpecWriter::odometry(const std::string& topic, std::int64_t log_time_ns,
                             std::int64_t stamp_ns, const std::string& frame,
                             const std::string& child, const io::Pose& pose) {
  writeMessage(topic, log_time_ns,
               Json{
                   {"header", headerJson(stamp_ns, frame)},
                   {"child_frame_id", child},
                   {"pose",
                    {{"pose",
                      {{"position", pointJson(pose.position)},
                       {"orientation", quaternionJson(pose.orientation)}}}}},
               });
}

void BagSpecWriter::cameraInfo(const std::string& topic, std::int64_t log_time_ns,
                               std::int64_t stamp_ns, const std::string& frame,
                               const CameraIntrinsics& c) {
  const bool distorted = c.distortion == DistortionModel::kPlumbBob;
  writeMessage(topic, log_time_ns,
               Json{
                   {"header", headerJson(stamp_ns, frame)},
                   {"height", c.height},
                   {"width", c.width},
                   {"distortion_model", distorted ? "plumb_bob" : ""},
                   {"d", {c.k1, c.k2, c.p1, c.p2, c.k3}},
                   {"k", {c.fx, 0.0, c.cx, 0.0, c.fy, c.cy, 0.0, 0.0, 1.0}},
                   {"r", {1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0}},
                   {"p", {c.fx, 0.0, c.cx, 0.0, 0.0, c.fy, c.cy, 0.0, 0.0, 0.0, 1.0, 0.0}},
               });
}

void BagSpecWriter::depthImage(const std::string& topic, std::int64_t log_time_ns,
                               std::int64_t stamp_ns, const std::string& frame, std::uint32_t width,
                               std::uint32_t height, std::span<const float> depth_m,
                               bool millimetres) {
  std::vector<std::byte> data;
  data.reserve(depth_m.size() * 4);
  for (const float d : depth_m) {
    if (millimetres) {
      const float mm = std::isfinite(d) && d > 0.0f ? std::round(d * 1000.0f) : 0.0f;
      const auto v = static_cast<std::uint16_t>(std::min(mm, 65535.0f));
      data.push_back(static_cast<std::byte>(v & 0xFFu));
      data.push_back(static_cast<std::byte>(v >> 8));
    } else {
      std::uint32_t bits = 0;
      std::memcpy(&bits, &d, sizeof(bits));
      for (int b = 0; b < 4; ++b) {
        data.push_back(static_cast<std::byte>((bits >> (8 * b)) & 0xFFu));
      }
    }
  }
  writeMessage(topic, log_time_ns,
               Json{
                   {"header", headerJson(stamp_ns, frame)},
                   {"height", height},
                   {"width", width},
                   {"encoding", millimetres ? "16UC1" : "32FC1"},
                   {"is_bigendian", 0},
                   {"step", width * (millimetres ? 2U : 4U)},
                   {"data", {{"base64", base64(data)}}},
               });
}

void BagSpecWriter::tf(const std::string& topic, std::int64_t log_time_ns,
                       const std::vector<SpecTransform>& transforms) {
  Json list = Json::array();
  for (const SpecTransform& t : transforms) {
    list.push_back(Json{
        {"header", headerJson(t.stamp_ns, t.parent)},
        {"child_frame_id", t.child},
        {"transform",
         {{"translation", pointJson(t.pose.position)},
          {"rotation", quaternionJson(t.pose.orientation)}}},
    });
  }
  writeMessage(topic, log_time_ns, Json{{"transforms", list}});
}

std::string base64(std::span<const std::byte> bytes) {
  static constexpr char kAlphabet[] =
      "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((bytes.size() + 2) / 3 * 4);
  for (std::size_t i = 0; i < bytes.size(); i += 3) {
    const std::size_t n = std::min<std::size_t>(3, bytes.size() - i);
    std::uint32_t v = 0;
    for (std::size_t k = 0; k < 3; ++k) {
      v = (v << 8) | (k < n ? static_cast<std::uint32_t>(bytes[i + k]) : 0u);
    }
    for (std::size_t k = 0; k < 4; ++k) {
      out += k <= n ? kAlphabet[(v >> (18 - 6 * k)) & 0x3Fu] : '=';
    }
  }
  return out;
}

}  // namespace raymap::test
