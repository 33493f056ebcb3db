// SPDX-License-Identifier: BSD-3-Clause
// The command line's memory options for maps larger than memory (--max-memory,
// --compressed-memory, --spill-dir, --no-tiers) and how the tiers are reported.
#pragma once

#include <optional>
#include <string>

#include "raymap/error.hpp"

#include "src/io/map_file.hpp"
#include "src/map/voxel_map.hpp"
#include "src/mapper/tier_report.hpp"
#include "tools/raymap/json_output.hpp"

namespace CLI {
class App;
}  // namespace CLI

namespace raymap::cli {

/// @brief The tier flags as typed. Shared by populate, bench, info, export and heightmap.
struct TierFlags {
  std::string compressed_memory = "1GiB";
  std::string spill_dir;  ///< empty: next to the first output (or the system's temporary folder)
  bool no_tiers = false;
};

/// @brief Registers --compressed-memory, --spill-dir and --no-tiers on a subcommand.
void addTierOptions(CLI::App& command, TierFlags& flags);

/// @brief The tier configuration the flags ask for. `output` (may be empty) gives the default
/// spill folder: the folder the output goes to; without one, $TMPDIR or /tmp. Errors name the
/// option.
Result<RegionTierConfig> toTierConfig(const TierFlags& flags, const std::string& output);

/// @brief Load options for a command that reads a map: the pool is --max-memory and a larger
/// file streams through the tiers (unless --no-tiers: then the whole file is loaded).
Result<io::MapLoadOptions> toLoadOptions(const std::string& max_memory, const TierFlags& flags,
                                         const std::string& output);

/// @brief Registers --max-memory (the region pool) on a subcommand that reads maps.
void addMaxMemoryOption(CLI::App& command, std::string& max_memory);

// The report of a tiered map and the check that it lost nothing are the library's.
using mapper::checkTiers;
using mapper::TierReport;
using mapper::tierReport;

/// @brief One line for a summary: pool use, compressed and spilled regions, ratio, waits.
std::string tierSummaryLine(const TierReport& report);
/// @brief A short text for the progress line ("pool 812/1024, cold 6,400 (spilled 3,000)").
std::string tierProgressText(const VoxelMap& map);
/// @brief The tiers as a JSON object (for --stats-json and info --json).
Json tierJson(const TierReport& report);

}  // namespace raymap::cli
