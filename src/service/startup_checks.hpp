// SPDX-License-Identifier: BSD-3-Clause
// What raymapd checks before it allocates anything: that every fixed pool its configuration asks
// for fits the memory this machine (and its limits) leave, and that the map can be saved where
// the configuration says. `raymapd --check-config` runs the same checks.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "raymap/error.hpp"

#include "platform/memory.hpp"
#include "src/service/daemon_config.hpp"

namespace raymap::service {

/// @brief One preallocation: the configuration key that sizes it and its bytes.
struct PoolEstimate {
  std::string key;   ///< e.g. "map.window", "queues.scan_slots x sensors[].max_points"
  std::string what;  ///< e.g. "region pool (12,800 regions of 393,216 bytes)"
  double bytes = 0;  ///< double: absurd configurations overflow 64-bit sizes
};

/// @brief Every fixed pool raymapd allocates at start-up for `config`, largest first: the map's
/// region pool, the scan slots, the integrator's batch, the pose queue and history, the voxel
/// topic's buffers. DDS's own receive buffers and a device backend's memory are not included.
std::vector<PoolEstimate> estimatePools(const DaemonConfig& config);

/// @brief Fails (kCapacity) when the pools add up to more than `limit` allows, naming the largest
/// pool's key, its bytes, the total and the limit's source; fails (kIo) when a file
/// dds.cyclonedds_uri names cannot be read, dds.receive_buffer_mb is more than the kernel allows,
/// or map.save_on_exit's folder does not exist or is not writable. Errors name the file, the key's
/// line and the key. Start-up only (allocates, reads the file system).
Expected<void, Error> checkStartup(const DaemonConfig& config, const platform::MemoryLimit& limit);

/// @brief The receive buffer raymapd asks for its DDS sockets, and why.
struct ReceiveBufferPlan {
  std::uint64_t bytes = 0;   ///< to ask Cyclone for (0: leave it to CYCLONEDDS_URI / Cyclone)
  std::uint64_t wanted = 0;  ///< what the sensors' clouds need at once (or dds.receive_buffer_mb)
  std::uint64_t cap = 0;     ///< net.core.rmem_max (0: unreadable)
  /// A warning for the log when `bytes` < `wanted` (the kernel's cap, what to set), else "".
  std::string warning;
};

/// @brief Sizes the socket receive buffer for the clouds `config` expects: a scan of every
/// sensor at once (max_points x 32 bytes a lidar point, 4 a depth pixel), at least 4 MiB, or
/// dds.receive_buffer_mb; at most what the kernel allows (`rmem_max`, net.core.rmem_max), with
/// a warning saying what to set when that is less. Fails (kCapacity) when dds.receive_buffer_mb
/// asks for more than the kernel allows (the domain could not be created). Pure.
Expected<ReceiveBufferPlan, Error> planReceiveBuffer(const DaemonConfig& config,
                                                     std::uint64_t rmem_max);

/// @brief A byte count for people: "25.8 GB", "393 KB".
std::string formatBytes(double bytes);

}  // namespace raymap::service
