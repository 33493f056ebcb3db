// SPDX-License-Identifier: BSD-3-Clause
// The replay tests' harness (see replay_harness.hpp).
#include "tests/replay/replay_harness.hpp"

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>

#include <gtest/gtest.h>

#include "platform/clock.hpp"
#include "tests/support/cli_runner.hpp"
#include "tests/support/json_doc.hpp"

namespace raymap::test {
namespace {

/// Cell centres lie half a cell off the multiples of the resolution: floor() names the cell
/// robustly where rounding would split ties by floating-point noise.
std::pair<long, long> cellKey(double x, double y, double resolution) {
  return {static_cast<long>(std::floor(x / resolution)),
          static_cast<long>(std::floor(y / resolution))};
}

}  // namespace

std::unique_ptr<DaemonProcess> startRaymap(const std::vector<std::string>& args,
                                           const std::string& log_path) {
  return std::make_unique<DaemonProcess>(RAYMAP_CLI_PATH, args, std::vector<std::string>{},
                                         log_path);
}

Daemon::Daemon(const TempDir& dir, const std::string& config_text, const std::string& name)
    : config_path(dir.file(name + ".yaml")), log_path(dir.file(name + ".log")) {
  std::ofstream(config_path) << config_text;
  process = std::make_unique<DaemonProcess>(RAYMAPD_PATH,
                                            std::vector<std::string>{"--config", config_path},
                                            std::vector<std::string>{}, log_path);
}

std::string Daemon::log() const { return readFile(log_path); }

Watcher::Watcher(std::uint32_t domain) {
  auto created = dds::Participant::create(domain);
  EXPECT_TRUE(created.has_value());
  participant.emplace(std::move(created).value());
  grid_maps = std::move(driver::GridMapListener::create(*participant, "rt/height_map")).value();
  diagnostics =
      std::move(driver::DiagnosticsListener::create(*participant, "rt/diagnostics")).value();
}

void Watcher::collect(double seconds, const std::function<bool()>& until) {
  const std::int64_t end = platform::monotonicNowNs() + static_cast<std::int64_t>(seconds * 1e9);
  while (platform::monotonicNowNs() < end) {
    grid_maps->poll(10'000'000, maps);
    diagnostics->poll();
    if (until && until()) {
      return;
    }
  }
}

void Watcher::collectUntilQuiet(double quiet_s, double max_s) {
  const std::int64_t quiet_ns = static_cast<std::int64_t>(quiet_s * 1e9);
  std::int64_t last_change = platform::monotonicNowNs();
  std::size_t seen = maps.size();
  collect(max_s, [&] {
    const std::int64_t now = platform::monotonicNowNs();
    if (maps.size() != seen) {
      seen = maps.size();
      last_change = now;
    }
    return now - last_change >= quiet_ns;
  });
}

std::optional<double> jsonNumber(const std::string& json, const std::string& key) {
  const std::optional<Json> document = parseJson(json);
  const Json* value = document ? findFirst(*document, key) : nullptr;
  if (value == nullptr || !value->is_number()) {
    return std::nullopt;
  }
  return value->get<double>();
}

OfflineHeights offlineHeights(const TempDir& dir, const std::string& input,
                              const std::vector<std::string>& populate_args, double centre_x,
                              double centre_y, double centre_z, double size) {
  static int run = 0;
  const std::string map = dir.file("offline" + std::to_string(run) + ".rmap");
  const std::string csv = dir.file("offline" + std::to_string(run++) + ".csv");
  std::vector<std::string> populate = {"populate", input, "-o", map, "-q"};
  populate.insert(populate.end(), populate_args.begin(), populate_args.end());
  const RunResult populated = runRaymap(populate);
  EXPECT_EQ(populated.exit_code, 0) << describe(populated);
  char centre[128];
  std::snprintf(centre, sizeof(centre), "%.6f,%.6f,%.6f", centre_x, centre_y, centre_z);
  const RunResult generated = runRaymap(
      {"heightmap", map, "--centre", centre, "--size", std::to_string(size), "--csv", csv, "-q"});
  EXPECT_EQ(generated.exit_code, 0) << describe(generated);
  OfflineHeights cells;
  std::ifstream in(csv);
  std::string line;
  std::getline(in, line);  // header
  const double resolution = 0.1;
  while (std::getline(in, line)) {
    std::stringstream fields(line);
    std::string x, y, elevation, clearance, kind;
    std::getline(fields, x, ',');
    std::getline(fields, y, ',');
    std::getline(fields, elevation, ',');
    std::getline(fields, clearance, ',');
    std::getline(fields, kind, ',');
    const auto key = cellKey(std::stod(x), std::stod(y), resolution);
    cells[key] = {std::strtof(elevation.c_str(), nullptr), kind == "surface"};
  }
  return cells;
}

Agreement compare(const driver::ReceivedGridMap& map, const OfflineHeights& offline) {
  Agreement a;
  const std::vector<float>* elevation = map.layer("elevation");
  const std::vector<float>* kind = map.layer("kind");
  if (elevation == nullptr || kind == nullptr) {
    return a;
  }
  const auto cells_x = static_cast<int>(std::lround(map.length_x / map.resolution));
  const auto cells_y = static_cast<int>(std::lround(map.length_y / map.resolution));
  for (int j = 0; j < cells_y; ++j) {
    for (int i = 0; i < cells_x; ++i) {
      // grid_map order: column-major, (0, 0) at the +x/+y corner.
      const std::size_t c = static_cast<std::size_t>(i + j * cells_x);
      const double x = map.centre_x + (0.5 * cells_x - i - 0.5) * map.resolution;
      const double y = map.centre_y + (0.5 * cells_y - j - 0.5) * map.resolution;
      const bool online = (*kind)[c] == 1.0F;  // RM_HM_SURFACE
      a.surface_online += online ? 1 : 0;
      const auto found = offline.find(cellKey(x, y, map.resolution));
      if (found == offline.end()) {
        a.not_found += online ? 1 : 0;
        continue;
      }
      a.surface_offline += found->second.surface ? 1 : 0;
      if (online && found->second.surface) {
        ++a.surface_both;
        if (std::fabs(static_cast<double>((*elevation)[c] - found->second.elevation)) <=
            map.resolution + 1e-4) {
          ++a.within_voxel;
        }
      }
    }
  }
  return a;
}

}  // namespace raymap::test
