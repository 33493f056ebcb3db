// SPDX-License-Identifier: BSD-3-Clause
// Memory-tier options and reports of the command line (see memory_tiers.hpp).
#include "tools/raymap/memory_tiers.hpp"

#include <cstdio>
#include <cstdlib>
#include <filesystem>

#include <CLI/CLI.hpp>

#include "src/core/byte_size.hpp"
#include "tools/raymap/cli_options.hpp"
#include "tools/raymap/commands.hpp"

namespace raymap::cli {
namespace {

std::string mib(std::uint64_t bytes) {
  char text[32];
  std::snprintf(text, sizeof text, "%.1f MiB", static_cast<double>(bytes) / (1024.0 * 1024.0));
  return text;
}

std::string defaultSpillFolder(const std::string& output) {
  if (!output.empty() && output != "-") {
    const std::filesystem::path parent = std::filesystem::path(output).parent_path();
    return parent.empty() ? std::string(".") : parent.string();
  }
  const char* tmp = std::getenv("TMPDIR");  // NOLINT(concurrency-mt-unsafe): start-up, one thread
  return tmp != nullptr && *tmp != '\0' ? std::string(tmp) : std::string("/tmp");
}

}  // namespace

void addTierOptions(CLI::App& c, TierFlags& f) {
  c.add_option("--compressed-memory", f.compressed_memory,
               "Memory for compressed regions once the pool (--max-memory) is full, e.g. 1GiB; "
               "past it the coldest go to the spill file")
      ->capture_default_str();
  c.add_option("--spill-dir", f.spill_dir,
               "Folder for the spill file of regions that fit neither budget (default: the "
               "output's folder; the file has no name and vanishes when raymap ends)");
  c.add_flag("--no-tiers", f.no_tiers,
             "Fail when the pool is full instead of moving cold regions out of it");
}

void addMaxMemoryOption(CLI::App& c, std::string& max_memory) {
  c.add_option("--max-memory", max_memory,
               "Region pool, e.g. 512MiB, 4GiB; a larger map streams through it (cold regions "
               "compressed, then spilled)")
      ->capture_default_str();
}

Result<RegionTierConfig> toTierConfig(const TierFlags& f, const std::string& output) {
  RegionTierConfig config;
  config.enabled = !f.no_tiers;
  auto bytes = parseByteSize(f.compressed_memory);
  if (!bytes) {
    return fail(ErrorCode::kInvalidArgument, "--compressed-memory: " + bytes.error().message);
  }
  config.compressed_bytes = *bytes;
  config.spill_dir = f.spill_dir.empty() ? defaultSpillFolder(output) : f.spill_dir;
  return config;
}

Result<io::MapLoadOptions> toLoadOptions(const std::string& max_memory, const TierFlags& f,
                                         const std::string& output) {
  io::MapLoadOptions options;
  auto budget = parseByteSize(max_memory);
  if (!budget) {
    return fail(ErrorCode::kInvalidArgument, "--max-memory: " + budget.error().message);
  }
  auto tiers = toTierConfig(f, output);
  if (!tiers) {
    return Unexpected(tiers.error());
  }
  options.tiers = *tiers;
  // Without tiers the whole file is loaded, as before: the budget only adds room.
  options.memory_budget_bytes = tiers->enabled ? *budget : 0;
  return options;
}

std::string tierSummaryLine(const TierReport& r) {
  const RegionTierStats& s = r.stats;
  char text[512];
  std::snprintf(text, sizeof text,
                "pool %s of %s regions; compressed %s (%s, ratio %.1f), spilled %s (file %s); %s "
                "evictions, %s restores, %s waits (%.2f s); %s batches split to fit the pool",
                withCommas(r.hot_regions).c_str(), withCommas(r.pool_regions).c_str(),
                withCommas(s.regions_compressed + s.regions_staged).c_str(),
                mib(s.compressed_bytes).c_str(), s.compressionRatio(),
                withCommas(s.regions_spilled).c_str(), mib(s.spill_file_bytes).c_str(),
                withCommas(s.evictions).c_str(), withCommas(s.restores).c_str(),
                withCommas(s.waits).c_str(), s.wait_seconds, withCommas(r.batches_split).c_str());
  return text;
}

std::string tierProgressText(const VoxelMap& map) {
  const auto s = map.tierStats();
  if (!s || s->evictions == 0) {
    return {};
  }
  return "pool " + withCommas(map.store().size()) + "/" + withCommas(map.store().capacity()) +
         ", cold " + withCommas(s->regions_staged + s->regions_compressed + s->regions_spilled) +
         " (spilled " + withCommas(s->regions_spilled) + ")";
}

Json tierJson(const TierReport& r) {
  const RegionTierStats& s = r.stats;
  return {
      {"pool_regions", r.pool_regions},
      {"regions_hot", r.hot_regions},
      {"regions_compressed", s.regions_compressed + s.regions_staged},
      {"regions_spilled", s.regions_spilled},
      {"batches_split", r.batches_split},
      {"compressed_bytes", s.compressed_bytes},
      {"compressed_peak_bytes", s.compressed_peak_bytes},
      {"compression_ratio", s.compressionRatio()},
      {"evictions", s.evictions},
      {"clean_evictions", s.clean_evictions},
      {"restores", s.restores},
      {"compressions", s.compressions},
      {"spill_writes", s.spill_writes},
      {"spill_bytes_written", s.spill_bytes_written},
      {"spill_reads", s.spill_reads},
      {"spill_bytes_read", s.spill_bytes_read},
      {"spill_file_bytes", s.spill_file_bytes},
      {"spill_garbage_bytes", s.spill_garbage_bytes},
      {"spill_compactions", s.spill_compactions},
      {"spill_bytes_reclaimed", s.spill_bytes_reclaimed},
      {"waits", s.waits},
      {"wait_seconds", s.wait_seconds},
      {"compress_seconds", s.compress_seconds},
      {"restore_seconds", s.restore_seconds},
  };
}

}  // namespace raymap::cli
