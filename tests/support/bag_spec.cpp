// SPDX-License-Identifier: BSD-3-Clause
#include "tests/support/bag_spec.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <vector>

namespace raymap::test {
namespace {

std::string timeJson(std::int64_t ns) {
  char text[96];
  const std::int64_t sec = ns >= 0 ? ns / 1000000000 : -((-ns + 999999999) / 1000000000);
  std::snprintf(text, sizeof(text), "{\"sec\":%lld,\"nanosec\":%lld}", static_cast<long long>(sec),
                static_cast<long long>(ns - sec * 1000000000));
  return text;
}

std::string headerJson(std::int64_t stamp_ns, const std::string& frame) {
  return "{\"stamp\":" + timeJson(stamp_ns) + ",\"frame_id\":\"" + frame + "\"}";
}

std::string poseJson(const io::Pose& p) {
  char text[320];
  std::snprintf(text, sizeof(text),
                "{\"position\":{\"x\":%.17g,\"y\":%.17g,\"z\":%.17g},\"orientation\":{\"x\":%.17g,"
                "\"y\":%.17g,\"z\":%.17g,\"w\":%.17g}}",
                p.position.x(), p.position.y(), p.position.z(), p.orientation.x(),
                p.orientation.y(), p.orientation.z(), p.orientation.w());
  return text;
}

/// `text` inside JSON quotes (quotes, backslashes and newlines escaped).
std::string escaped(const std::string& text) {
  std::string out;
  for (const char c : text) {
    if (c == '\n') {
      out += "\\n";
    } else {
      if (c == '"' || c == '\\') {
        out += '\\';
      }
      out += c;
    }
  }
  return out;
}

template <class T>
void put(std::vector<std::byte>& out, std::size_t at, T value) {
  std::memcpy(out.data() + at, &value, sizeof(T));  // little-endian host (x86, ARM)
}

}  // namespace

BagSpecWriter::BagSpecWriter(const std::string& path) : out_(path) {}

void BagSpecWriter::channel(const std::string& topic, const std::string& type,
                            const std::string& qos) {
  out_ << "{\"op\":\"channel\",\"topic\":\"" << topic << "\",\"type\":\"" << type << "\",\"qos\":\""
       << escaped(qos) << "\"}\n";
}

void BagSpecWriter::message(const std::string& topic, std::int64_t log_time_ns,
                            const std::string& body) {
  out_ << "{\"op\":\"message\",\"topic\":\"" << topic << "\",\"log_time_ns\":\"" << log_time_ns
       << "\",\"publish_time_ns\":\"" << log_time_ns << "\",\"msg\":" << body << "}\n";
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
  const std::string fields =
      "[{\"name\":\"x\",\"offset\":0,\"datatype\":7,\"count\":1},"
      "{\"name\":\"y\",\"offset\":4,\"datatype\":7,\"count\":1},"
      "{\"name\":\"z\",\"offset\":8,\"datatype\":7,\"count\":1},"
      "{\"name\":\"intensity\",\"offset\":16,\"datatype\":7,\"count\":1},"
      "{\"name\":\"t\",\"offset\":20,\"datatype\":6,\"count\":1},"
      "{\"name\":\"ring\",\"offset\":26,\"datatype\":4,\"count\":1}]";
  message(
      topic, log_time_ns,
      "{\"header\":" + headerJson(stamp_ns, frame) +
          ",\"height\":1,\"width\":" + std::to_string(points.size()) + ",\"fields\":" + fields +
          ",\"is_bigendian\":false,\"point_step\":48,\"row_step\":" + std::to_string(data.size()) +
          ",\"data\":{\"base64\":\"" + base64(data) + "\"},\"is_dense\":true}");
}

void BagSpecWriter::odometry(const std::string& topic, std::int64_t log_time_ns,
                             std::int64_t stamp_ns, const std::string& frame,
                             const std::string& child, const io::Pose& pose) {
  message(topic, log_time_ns,
          "{\"header\":" + headerJson(stamp_ns, frame) + ",\"child_frame_id\":\"" + child +
              "\",\"pose\":{\"pose\":" + poseJson(pose) + "}}");
}

void BagSpecWriter::cameraInfo(const std::string& topic, std::int64_t log_time_ns,
                               std::int64_t stamp_ns, const std::string& frame,
                               const CameraIntrinsics& c) {
  const bool distorted = c.distortion == DistortionModel::kPlumbBob;
  char body[1024];
  std::snprintf(body, sizeof(body),
                ",\"height\":%u,\"width\":%u,\"distortion_model\":\"%s\","
                "\"d\":[%.17g,%.17g,%.17g,%.17g,%.17g],"
                "\"k\":[%.17g,0,%.17g,0,%.17g,%.17g,0,0,1],\"r\":[1,0,0,0,1,0,0,0,1],"
                "\"p\":[%.17g,0,%.17g,0,0,%.17g,%.17g,0,0,0,1,0]}",
                c.height, c.width, distorted ? "plumb_bob" : "", c.k1, c.k2, c.p1, c.p2, c.k3, c.fx,
                c.cx, c.fy, c.cy, c.fx, c.cx, c.fy, c.cy);
  message(topic, log_time_ns, "{\"header\":" + headerJson(stamp_ns, frame) + body);
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
  char fields[256];
  std::snprintf(fields, sizeof(fields),
                ",\"height\":%u,\"width\":%u,\"encoding\":\"%s\",\"is_bigendian\":0,"
                "\"step\":%u,\"data\":{\"base64\":\"",
                height, width, millimetres ? "16UC1" : "32FC1", width * (millimetres ? 2u : 4u));
  message(topic, log_time_ns,
          "{\"header\":" + headerJson(stamp_ns, frame) + fields + base64(data) + "\"}}");
}

void BagSpecWriter::tf(const std::string& topic, std::int64_t log_time_ns,
                       const std::vector<SpecTransform>& transforms) {
  std::string list;
  for (const SpecTransform& t : transforms) {
    char translation[160];
    std::snprintf(translation, sizeof(translation), "{\"x\":%.17g,\"y\":%.17g,\"z\":%.17g}",
                  t.pose.position.x(), t.pose.position.y(), t.pose.position.z());
    char rotation[200];
    std::snprintf(rotation, sizeof(rotation), "{\"x\":%.17g,\"y\":%.17g,\"z\":%.17g,\"w\":%.17g}",
                  t.pose.orientation.x(), t.pose.orientation.y(), t.pose.orientation.z(),
                  t.pose.orientation.w());
    if (!list.empty()) {
      list += ',';
    }
    list.append("{\"header\":")
        .append(headerJson(t.stamp_ns, t.parent))
        .append(",\"child_frame_id\":\"")
        .append(t.child)
        .append("\",\"transform\":{\"translation\":")
        .append(translation)
        .append(",\"rotation\":")
        .append(rotation)
        .append("}}");
  }
  message(topic, log_time_ns, "{\"transforms\":[" + list + "]}");
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
