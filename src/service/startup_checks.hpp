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
/// dds.cyclonedds_uri names cannot be read, or map.save_on_exit's folder does not exist or is not
/// writable. Errors name the file, the key's line and the key. Start-up only (allocates, reads the
/// file system).
Expected<void, Error> checkStartup(const DaemonConfig& config, const platform::MemoryLimit& limit);

/// @brief A byte count for people: "25.8 GB", "393 KB".
std::string formatBytes(double bytes);

}  // namespace raymap::service
