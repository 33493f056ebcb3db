// SPDX-License-Identifier: BSD-3-Clause
// Start-up checks of raymapd (see the header).
#include "src/service/startup_checks.hpp"

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>

#include <unistd.h>

#include "platform/socket_buffers.hpp"
#include "src/map/ray.hpp"
#include "src/msgs/point_cloud.hpp"
#include "src/pipeline/pose_update.hpp"

namespace raymap::service {
namespace {

/// The slack between the pools and the limit: threads' stacks, DDS, libraries, the heap.
constexpr double kHeadroomBytes = 256.0 * 1024 * 1024;

std::string thousands(double n) {
  char digits[64];
  std::snprintf(digits, sizeof(digits), "%.0f", n);
  std::string out;
  const std::string s = digits;
  for (std::size_t i = 0; i < s.size(); ++i) {
    if (i > 0 && (s.size() - i) % 3 == 0) {
      out += ',';
    }
    out += s[i];
  }
  return out;
}

}  // namespace

std::string formatBytes(double bytes) {
  static const char* const kUnits[] = {"bytes", "KB", "MB", "GB", "TB", "PB", "EB"};
  int unit = 0;
  while (bytes >= 1000.0 && unit < 6) {
    bytes /= 1000.0;
    ++unit;
  }
  char text[64];
  std::snprintf(text, sizeof(text), unit == 0 ? "%.0f %s" : "%.1f %s", bytes, kUnits[unit]);
  return text;
}

std::vector<PoolEstimate> estimatePools(const DaemonConfig& config) {
  std::vector<PoolEstimate> pools;
  const MapConfig& map = config.map;
  // The region pool: every window region's layers, plus the store's per-slot bookkeeping.
  const double regions =
      static_cast<double>(map.window_regions.x) * map.window_regions.y * map.window_regions.z;
  const double region_bytes =
      static_cast<double>(map.schema().bytesPerRegion(map.geometry.voxelsPerRegion()));
  pools.push_back(
      {"map.window",
       "region pool (" + thousands(regions) + " regions of " + thousands(region_bytes) + " bytes)",
       regions * (region_bytes + 64.0)});
  std::uint32_t max_points = 1;
  for (const SensorConfig& s : config.sensors) {
    max_points = std::max(max_points, s.max_points);
  }
  double ray_table_pixels = 0.0;
  for (const SensorConfig& s : config.sensors) {
    ray_table_pixels += static_cast<double>(depthRayTablePixels(s));
  }
  if (ray_table_pixels > 0.0) {
    pools.push_back({"sensors[].max_points x downsample^2 (depth cameras)",
                     "depth cameras' pixel rays (" + thousands(ray_table_pixels) + " pixels)",
                     ray_table_pixels * 2.0 * sizeof(float)});
  }
  const double slots = config.queues.scan_slots + 1.0;
  pools.push_back(
      {"queues.scan_slots x sensors[].max_points",
       "decoded scan slots (" + thousands(slots) + " of " + thousands(max_points) + " points)",
       slots * max_points * static_cast<double>(sizeof(msgs::ScanPoint))});
  // The integrator's batch: whole scans under per-scan semantics.
  const double batch = map.semantics == Semantics::kPerScan
                           ? std::max<double>(config.queues.batch_rays, max_points)
                           : config.queues.batch_rays;
  pools.push_back({"queues.batch_rays", "integrator batch (" + thousands(batch) + " rays)",
                   batch * static_cast<double>(sizeof(Ray) + sizeof(PreparedRay))});
  pools.push_back({"queues.pose_queue, pose.history", "pose queue and history",
                   (static_cast<double>(config.queues.pose_queue) + config.pose.history) *
                       static_cast<double>(sizeof(pipeline::PoseUpdate))});
  if (!config.dds.voxels_topic.empty()) {
    pools.push_back({"dds.voxels_max_points", "occupied-voxel buffers",
                     static_cast<double>(config.dds.voxels_max_points) * 28.0});
  }
  std::sort(pools.begin(), pools.end(),
            [](const PoolEstimate& a, const PoolEstimate& b) { return a.bytes > b.bytes; });
  return pools;
}

namespace {

/// dds.cyclonedds_uri: Cyclone's list of configuration sources, separated by commas: inline XML
/// (starting with '<') or files (file://PATH, or a bare path). Every file must be readable: a
/// missing one would otherwise surface as a failed participant at start.
Expected<void, Error> checkCycloneUri(const DaemonConfig& config) {
  const std::string& uri = config.dds.cyclonedds_uri;
  std::size_t begin = 0;
  while (begin <= uri.size() && !uri.empty()) {
    std::size_t end = uri.find(',', begin);
    // A comma inside inline XML is not a separator: the element runs to its closing '>'.
    std::string item = uri.substr(begin, end == std::string::npos ? end : end - begin);
    const std::size_t first = item.find_first_not_of(" \t\n");
    item = first == std::string::npos ? std::string() : item.substr(first);
    if (!item.empty() && item.front() == '<') {
      const std::size_t closing = uri.find('>', begin);
      end = closing == std::string::npos ? std::string::npos : uri.find(',', closing);
    } else if (!item.empty()) {
      const std::string file = item.rfind("file://", 0) == 0 ? item.substr(7) : item;
      std::FILE* f = std::fopen(file.c_str(), "rb");
      if (f == nullptr) {
        return fail(ErrorCode::kIo, config.where("dds.cyclonedds_uri") + ": cannot read " + file +
                                        ": " + std::strerror(errno));
      }
      std::fclose(f);
    }
    if (end == std::string::npos) {
      break;
    }
    begin = end + 1;
  }
  return {};
}

}  // namespace

Expected<ReceiveBufferPlan, Error> planReceiveBuffer(const DaemonConfig& config,
                                                     std::uint64_t rmem_max) {
  constexpr std::uint64_t kMiB = std::uint64_t{1} << 20;
  ReceiveBufferPlan plan;
  plan.cap = rmem_max;
  const std::string sysctl_hint =
      " (sysctl -w net.core.rmem_max=N, and a file in /etc/sysctl.d/ "
      "to keep it; docs/raymapd.md, DDS transport)";
  if (config.dds.receive_buffer_mb > 0) {
    plan.wanted = std::uint64_t{config.dds.receive_buffer_mb} * kMiB;
    if (rmem_max > 0 && plan.wanted > rmem_max) {
      return fail(ErrorCode::kCapacity,
                  config.where("dds.receive_buffer_mb") + ": " +
                      formatBytes(static_cast<double>(plan.wanted)) +
                      " is more than the kernel allows a socket (net.core.rmem_max " +
                      formatBytes(static_cast<double>(rmem_max)) + "): raise it to " +
                      std::to_string(plan.wanted) + sysctl_hint + ", or ask for less");
    }
  } else {
    // A scan of every sensor at once: the burst of datagrams the receive thread drains.
    std::uint64_t burst = 0;
    for (const SensorConfig& sensor : config.sensors) {
      burst += std::uint64_t{sensor.max_points} * (sensor.kind == SensorKind::kDepth ? 4u : 32u);
    }
    plan.wanted = std::max<std::uint64_t>(4 * kMiB, burst);
  }
  if (rmem_max == 0) {
    plan.warning =
        "socket receive buffer: cannot read net.core.rmem_max: left to Cyclone DDS "
        "(1 MiB if the kernel allows it); the sensors' clouds want " +
        formatBytes(static_cast<double>(plan.wanted));
    return plan;
  }
  plan.bytes = std::min(plan.wanted, rmem_max);
  if (plan.bytes < plan.wanted) {
    plan.warning = "socket receive buffer: the sensors' clouds want " +
                   formatBytes(static_cast<double>(plan.wanted)) +
                   " at once, but the kernel allows " + formatBytes(static_cast<double>(rmem_max)) +
                   " (net.core.rmem_max): bursts of clouds may be lost (counted as clouds_missing "
                   "and socket_datagrams_dropped). Raise it to " +
                   std::to_string(plan.wanted) + sysctl_hint;
  }
  return plan;
}

Expected<void, Error> checkStartup(const DaemonConfig& config, const platform::MemoryLimit& limit) {
  const std::vector<PoolEstimate> pools = estimatePools(config);
  double total = 0.0;
  for (const PoolEstimate& p : pools) {
    total += p.bytes;
  }
  const double available = static_cast<double>(limit.bytes);
  if (total + kHeadroomBytes > available) {
    const PoolEstimate& largest = pools.front();
    return fail(ErrorCode::kCapacity,
                config.where(largest.key) + ": needs " + formatBytes(largest.bytes) + " for the " +
                    largest.what + "; with the other pools raymapd would take " +
                    formatBytes(total) + " (+ " + formatBytes(kHeadroomBytes) +
                    " for threads and DDS), more than the " + formatBytes(available) +
                    " this machine leaves it (" + limit.source +
                    "): make it smaller, or free memory");
  }
  if (auto uri = checkCycloneUri(config); !uri) {
    return uri;
  }
  if (auto buffer = planReceiveBuffer(config, platform::socketReceiveBufferCap()); !buffer) {
    return Unexpected(std::move(buffer).error());
  }
  const std::string& save = config.save_map_on_exit;
  if (!save.empty()) {
    std::filesystem::path dir = std::filesystem::path(save).parent_path();
    if (dir.empty()) {
      dir = ".";
    }
    std::error_code ec;
    const std::filesystem::file_status target = std::filesystem::status(save, ec);
    if (!ec && std::filesystem::exists(target) && !std::filesystem::is_regular_file(target)) {
      return fail(
          ErrorCode::kIo,
          config.where("map.save_on_exit") + ": " + save + " is " +
              (std::filesystem::is_directory(target) ? "a directory" : "not a regular file") +
              ": name the map file to write (the map would be lost at shutdown)");
    }
    if (!std::filesystem::is_directory(dir, ec)) {
      return fail(ErrorCode::kIo, config.where("map.save_on_exit") + ": the folder " +
                                      dir.string() +
                                      " does not exist (the map would be lost at shutdown)");
    }
    if (::access(dir.c_str(), W_OK | X_OK) != 0) {
      return fail(ErrorCode::kIo, config.where("map.save_on_exit") + ": the folder " +
                                      dir.string() +
                                      " is not writable by this user (the map would be lost "
                                      "at shutdown)");
    }
  }
  return {};
}

}  // namespace raymap::service
