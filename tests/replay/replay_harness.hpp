// SPDX-License-Identifier: BSD-3-Clause
// The replay tests' harness: raymapd and `raymap replay` / `raymap record` as separate processes
// on a test domain, an independent GridMap and diagnostics subscriber, and the offline
// `raymap populate` + `raymap heightmap` of the same data to compare with.
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "src/dds/entities.hpp"
#include "src/driver/ros_endpoints.hpp"
#include "tests/service/daemon_process.hpp"
#include "tests/support/temp_dir.hpp"

namespace raymap::test {

/// @brief `raymap` with `args` as a child process, its output in `log_path`.
std::unique_ptr<DaemonProcess> startRaymap(const std::vector<std::string>& args,
                                           const std::string& log_path);

/// @brief raymapd from a configuration text written into `dir`.
struct Daemon {
  Daemon(const TempDir& dir, const std::string& config_text, const std::string& name = "raymapd");
  std::string log() const;
  std::string config_path, log_path;
  std::unique_ptr<DaemonProcess> process;
};

/// @brief The subscriber side: GridMaps and diagnostics, in their own participant.
struct Watcher {
  explicit Watcher(std::uint32_t domain);
  /// @brief Collects for `seconds` (or until `until` returns true).
  void collect(double seconds, const std::function<bool()>& until = nullptr);
  /// @brief Collects until no GridMap has arrived for `quiet_s`, at most `max_s`: after the
  /// input ended, raymapd publishes until its map goes stale (health.stale_after_s after the
  /// last scan went in) and then withholds it, so a quiet topic means every map with the last
  /// scans in it has been received, however long a slow machine took to get there.
  void collectUntilQuiet(double quiet_s, double max_s);
  std::optional<dds::Participant> participant;
  std::unique_ptr<driver::GridMapListener> grid_maps;
  std::unique_ptr<driver::DiagnosticsListener> diagnostics;
  std::vector<driver::ReceivedGridMap> maps;
};

/// @brief The first number named `key` in the JSON document `json` (document order); nullopt
/// when there is none. Text that is not JSON is a test failure (parseJson).
std::optional<double> jsonNumber(const std::string& json, const std::string& key);

/// @brief One height-map cell of the offline `raymap heightmap --csv`.
struct OfflineCell {
  float elevation;
  bool surface;
};
/// @brief Cells by (floor(x / resolution), floor(y / resolution)) of their centres.
using OfflineHeights = std::map<std::pair<long, long>, OfflineCell>;

/// @brief `raymap populate INPUT` then `raymap heightmap` around (x, y, z) with `size` metres,
/// read back from its CSV. `populate_args` are extra populate options (ranges, resolution).
OfflineHeights offlineHeights(const TempDir& dir, const std::string& input,
                              const std::vector<std::string>& populate_args, double centre_x,
                              double centre_y, double centre_z, double size);

/// @brief How a received GridMap compares with the offline height map of the same data.
struct Agreement {
  int surface_both = 0;     ///< surface cells in both
  int within_voxel = 0;     ///< of those, heights within one voxel (the resolution)
  int surface_online = 0;   ///< surface cells of the GridMap
  int surface_offline = 0;  ///< surface cells of the offline map that the GridMap covers
  int not_found = 0;        ///< GridMap surface cells outside the offline map
  double fraction() const { return surface_both == 0 ? 0.0 : double(within_voxel) / surface_both; }
};
Agreement compare(const driver::ReceivedGridMap& map, const OfflineHeights& offline);

}  // namespace raymap::test
