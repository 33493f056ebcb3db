// SPDX-License-Identifier: BSD-3-Clause
// raymap-decode-bench: how fast raymapd's PointCloud2 decoder (msgs::decodePointCloud2, the one
// the DDS readers and the bag reader call) turns a lidar's message into points, on Ouster clouds
// serialized as the driver publishes them (msgs::serializeOusterCloud). Beside each, a plain
// copy of the message's bytes: the floor any decoder pays.
// Prints JSON: medians of the repetitions. Run: build/release/tools/raymap-decode-bench [reps]
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <numbers>
#include <string>
#include <vector>

#include "src/msgs/point_cloud.hpp"
#include "src/msgs/point_cloud_writer.hpp"
#include "tools/raymap/json_output.hpp"

namespace {

using namespace raymap;
using Clock = std::chrono::steady_clock;

constexpr std::int64_t kStampNs = 1'700'000'000'000'000'000;
constexpr double kSweepS = 0.1;  // 10 Hz: the columns' times span a tenth of a second

/// A scan of `beams` x `columns` points as an OS-1 sees a room: ranges of 1 to 20 m varying with
/// azimuth and beam, about 3 % without a return (sky, glass).
std::vector<msgs::ScanPoint> ousterScan(std::uint32_t beams, std::uint32_t columns) {
  std::vector<msgs::ScanPoint> points;
  points.reserve(std::size_t{beams} * columns);
  for (std::uint32_t b = 0; b < beams; ++b) {
    const double elevation =
        (-22.5 + 45.0 * b / std::max(beams - 1, 1u)) * std::numbers::pi / 180.0;
    for (std::uint32_t c = 0; c < columns; ++c) {
      const double azimuth = 2.0 * std::numbers::pi * c / columns;
      const double range = 1.0 + 19.0 * (0.5 + 0.5 * std::sin(3.0 * azimuth + 0.1 * b));
      msgs::ScanPoint p{};
      p.x = static_cast<float>(range * std::cos(elevation) * std::cos(azimuth));
      p.y = static_cast<float>(range * std::cos(elevation) * std::sin(azimuth));
      p.z = static_cast<float>(range * std::sin(elevation));
      p.time_s = static_cast<float>(kSweepS * c / columns);
      p.intensity = static_cast<float>((b * 31 + c * 17) % 1000);
      p.flags = (b * columns + c) % 33 == 7 ? msgs::kPointNoReturn : 0u;
      points.push_back(p);
    }
  }
  return points;
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

/// Seconds per call of `run`, median over `repetitions` timings of `calls` calls each.
template <typename Run>
double secondsPerCall(int repetitions, int calls, Run&& run) {
  std::vector<double> seconds;
  for (int r = 0; r < repetitions; ++r) {
    const auto start = Clock::now();
    for (int k = 0; k < calls; ++k) {
      run();
    }
    seconds.push_back(std::chrono::duration<double>(Clock::now() - start).count() / calls);
  }
  return median(seconds);
}

[[noreturn]] void die(const std::string& message) {
  std::fprintf(stderr, "raymap-decode-bench: %s\n", message.c_str());
  std::exit(1);
}

/// One case: the message decoded with `options`, and its bytes copied, per call.
cli::Json decodeCase(const char* name, std::uint32_t beams, std::uint32_t columns,
                     const msgs::CloudDecodeOptions& options, int repetitions) {
  const std::vector<msgs::ScanPoint> scan = ousterScan(beams, columns);
  std::vector<std::byte> message;
  msgs::serializeOusterCloud(kStampNs, "os_sensor", beams, scan, {}, message);
  std::vector<msgs::ScanPoint> points(scan.size());
  std::vector<std::byte> copy(message.size());
  std::uint32_t decoded = 0;
  const int calls = std::max(1, static_cast<int>(20'000'000 / scan.size()));
  const double decode_s = secondsPerCall(repetitions, calls, [&] {
    const auto header = msgs::decodePointCloud2(message, points, options);
    if (!header) {
      die(std::string("decode: ") + msgs::toString(header.error()));
    }
    decoded = header->points;
  });
  const double copy_s = secondsPerCall(repetitions, calls, [&] {
    std::memcpy(copy.data(), message.data(), message.size());
    asm volatile("" : : "r"(copy.data()) : "memory");  // keep the copy
  });
  const double n = static_cast<double>(decoded);
  return {
      {"case", name},
      {"points", decoded},
      {"message_bytes", message.size()},
      {"ns_per_point", decode_s * 1e9 / n},
      {"m_points_per_s", n / decode_s / 1e6},
      {"message_mb_per_s", static_cast<double>(message.size()) / decode_s / 1e6},
      {"ms_per_message", decode_s * 1e3},
      {"copy_ns_per_point", copy_s * 1e9 / n},
      {"decode_over_copy", decode_s / copy_s},
  };
}

}  // namespace

int main(int argc, char** argv) {
  int repetitions = 7;
  if (argc > 1) {
    const std::string arg = argv[1];
    if (arg == "--help" || arg == "-h" || argc > 2) {
      std::printf("usage: raymap-decode-bench [repetitions (at least 5; default 7)]\n");
      return arg == "--help" || arg == "-h" ? 0 : 2;
    }
    repetitions = std::max(5, std::atoi(arg.c_str()));
  }
  msgs::CloudDecodeOptions all;  // time ("t", ns after the stamp) and intensity: raymapd's use
  msgs::CloudDecodeOptions xyz_only;
  xyz_only.ignore_time = true;
  xyz_only.intensity_field = nullptr;
  cli::Json cases = cli::Json::array();
  cases.push_back(
      decodeCase("OS-1-128 1024 columns, x y z t intensity", 128, 1024, all, repetitions));
  cases.push_back(decodeCase("OS-1-128 1024 columns, x y z", 128, 1024, xyz_only, repetitions));
  cases.push_back(
      decodeCase("OS-1-128 2048 columns, x y z t intensity", 128, 2048, all, repetitions));
  cases.push_back(decodeCase("OS-1-64 512 columns, x y z t intensity", 64, 512, all, repetitions));
  const cli::Json result = {
      {"benchmark", "raymap-decode-bench"},
      {"decoder", "msgs::decodePointCloud2 (Ouster driver layout, 48-byte points, CDR_LE)"},
      {"repetitions", repetitions},
      {"cases", cases},
  };
  std::printf("%s\n", cli::dumpJson(result).c_str());
  return 0;
}
