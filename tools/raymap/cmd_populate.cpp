// SPDX-License-Identifier: BSD-3-Clause
// `raymap populate`: build a map from a recorded file.
#include <algorithm>
#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <memory>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "src/bag/bag_reader.hpp"
#include "src/io/map_export.hpp"
#include "src/io/map_file.hpp"
#include "src/io/staged_outputs.hpp"
#include "src/mapper/pool_fit.hpp"
#include "tools/raymap/cli_options.hpp"
#include "tools/raymap/commands.hpp"
#include "tools/raymap/json_output.hpp"
#include "tools/raymap/option_names.hpp"
#include "tools/raymap/populate.hpp"

namespace raymap::cli {
namespace {

struct PopulateFlags {
  std::string input;
  MappingFlags mapping;
  std::string output;
  std::string ply;
  std::string stats_json;
  bool quiet = false;
};

/// Why rays were rejected, by reason: "invalid 0, too short 12, out of bounds or longer than
/// --max-ray-length 0".
std::string rejectionsText(const RayCounters& rays) {
  return "invalid " + withCommas(rays.rays_invalid) + ", too short " +
         withCommas(rays.rays_too_short) + ", out of bounds or longer than --max-ray-length " +
         withCommas(rays.rays_out_of_bounds);
}

/// The bag's messages, clouds, poses, points and depth-image counters.
void printBagLines(const bag::BagRaysReport& b) {
  std::string topics;
  for (const std::string& t : b.cloud_topics) {
    topics += (topics.empty() ? "" : ", ") + t;
  }
  std::printf(
      "bag            %s messages; clouds on %s: %s, %s mapped, %s without a pose, %s "
      "skipped; poses from %s: %s (%s out of order)\n",
      withCommas(b.messages).c_str(), topics.c_str(), withCommas(b.clouds).c_str(),
      withCommas(b.scans_integrated).c_str(), withCommas(b.scans_no_pose).c_str(),
      withCommas(b.clouds_skipped).c_str(), b.pose_source.c_str(), withCommas(b.poses).c_str(),
      withCommas(b.poses_out_of_order).c_str());
  std::printf(
      "               %s points without return, %s with a bad time; TF: %u extrinsics, %s "
      "ignored, %s unresolved\n",
      withCommas(b.points_no_return).c_str(), withCommas(b.points_bad_time).c_str(),
      b.extrinsics_from_tf, withCommas(b.tf_ignored).c_str(), withCommas(b.tf_unresolved).c_str());
  if (b.camera_infos + b.camera_infos_skipped + b.images_no_camera_info + b.rate_limited > 0) {
    std::printf(
        "               depth: %s CameraInfo used, %s refused, %s images before their "
        "CameraInfo; %s messages above --max-rate\n",
        withCommas(b.camera_infos).c_str(), withCommas(b.camera_infos_skipped).c_str(),
        withCommas(b.images_no_camera_info).c_str(), withCommas(b.rate_limited).c_str());
  }
}

/// What the map holds, by kind of map.
void printMapLine(const PopulateReport& r, const PopulateOptions& o) {
  if (o.map.mode == MapMode::kTsdf) {
    std::printf(
        "map            %s TSDF voxels updated (%s behind the surface) in %s regions (%.3g m, "
        "truncation %g m)\n",
        withCommas(r.tsdf.updated).c_str(), withCommas(r.tsdf.behind).c_str(),
        withCommas(r.summary.regions).c_str(), o.map.geometry.resolution,
        o.map.tsdf.truncationMetres(o.map.geometry.resolution));
  } else if (!o.map.occupancy_layer) {
    std::printf(
        "map            %s voxels crossed (%s with samples) in %s regions (%.3g m, decay rates "
        "only)\n",
        withCommas(r.decay.crossed).c_str(), withCommas(r.decay.with_samples).c_str(),
        withCommas(r.summary.regions).c_str(), o.map.geometry.resolution);
  } else {
    std::printf(
        "map            %s free, %s occupied voxels in %s regions (%.3g m, %s semantics, %s)\n",
        withCommas(r.summary.voxels_free).c_str(), withCommas(r.summary.voxels_occupied).c_str(),
        withCommas(r.summary.regions).c_str(), o.map.geometry.resolution, toString(o.map.semantics),
        mapModeName(o.map).c_str());
  }
}

void printSummary(const PopulateReport& r, const PopulateOptions& o) {
  const double rate = r.integrate_seconds > 0
                          ? static_cast<double>(r.rays.rays_accepted) / r.integrate_seconds
                          : 0.0;
  std::printf("input          %s\n", o.input.c_str());
  std::printf("rays           %s in, %s integrated, %s rejected",
              withCommas(r.rays.rays_in).c_str(), withCommas(r.rays.rays_accepted).c_str(),
              withCommas(r.rays.rejected()).c_str());
  if (r.rays.rejected() > 0) {
    std::printf(" (%s)", rejectionsText(r.rays).c_str());
  }
  std::printf("\n               %s clipped to max range, %s without return, %s scans\n",
              withCommas(r.rays.rays_clipped).c_str(), withCommas(r.rays.rays_no_return).c_str(),
              withCommas(r.scans).c_str());
  if (r.bag) {
    printBagLines(*r.bag);
  }
  printMapLine(r, o);
  if (r.tiers && r.tiers->stats.evictions > 0) {
    std::printf("memory tiers   %s\n", tierSummaryLine(*r.tiers).c_str());
  }
  if (r.device.empty()) {
    std::printf("integration    %.3f s, %.3g M rays/s (%s, %u threads); reading %.3f s\n",
                r.integrate_seconds, rate / 1e6, r.backend_name.c_str(), r.threads, r.read_seconds);
    return;
  }
  const BackendStats& b = r.backend;
  std::printf("integration    %.3f s, %.3g M rays/s (%s on %s); reading %.3f s\n",
              r.integrate_seconds, rate / 1e6, r.backend_name.c_str(), r.device.c_str(),
              r.read_seconds);
  std::printf(
      "device         %s updates dropped, %s rays skipped; cache %s slots, %s hits, %s "
      "misses, %s evictions; %s MB to the device, %s MB back\n",
      withCommas(b.updates_dropped).c_str(), withCommas(b.rays_skipped).c_str(),
      withCommas(b.cache_slots).c_str(), withCommas(b.cache_hits).c_str(),
      withCommas(b.cache_misses).c_str(), withCommas(b.cache_evictions).c_str(),
      withCommas(b.bytes_to_device >> 20).c_str(), withCommas(b.bytes_from_device >> 20).c_str());
}

/// The staged names of populate's outputs (empty where not asked for, or "-").
struct PopulateTemps {
  std::string output, ply, stats;
};

/// Stages every output under a temporary name; prints why not and returns the exit code (0 when
/// all were staged).
int stageOutputs(const PopulateFlags& f, io::StagedOutputs& staged, PopulateTemps& temps) {
  staged.input(f.input, "the input");
  staged.input(f.mapping.trajectory, "--trajectory");
  for (const auto& [path, name, temp] :
       {std::tuple{&f.output, "--output", &temps.output}, std::tuple{&f.ply, "--ply", &temps.ply},
        std::tuple{&f.stats_json, "--stats-json", &temps.stats}}) {
    if (!path->empty() && *path != "-") {
      auto staged_path = staged.add(*path, name);
      if (!staged_path) {
        printError("populate", staged_path.error().message);
        return exitCodeFor(staged_path.error());
      }
      *temp = std::move(*staged_path);
    }
  }
  return kExitOk;
}

/// The run's warnings and a bag's notes, on stderr.
void printWarnings(const PopulateReport& report, bool quiet) {
  const auto warn = [](const std::string& text) {
    std::fprintf(stderr, "raymap populate: warning: %s\n", withCliFlags(text).c_str());
  };
  for (const std::string* warning :
       {&report.fallback_warning, &report.startup_warning, &report.input_warning}) {
    if (!warning->empty()) {
      warn(*warning);
    }
  }
  if (!report.bag) {
    return;
  }
  const bag::BagRaysReport& b = *report.bag;
  if (!b.pose_note.empty() && !quiet) {
    std::fprintf(stderr, "raymap populate: note: %s\n", withCliFlags(b.pose_note).c_str());
  }
  for (const std::string& warning : b.read_warnings) {
    warn(warning);
  }
  for (const std::string& damage : b.damage) {
    warn("--skip-damaged: " + damage);
  }
  for (const std::string& skip : b.skips) {
    warn(skip);
  }
}

/// An empty map from a whole input is a failure, never a result: says why each cloud or ray
/// went and returns false.
bool somethingMapped(const PopulateReport& report, const PopulateOptions& options) {
  if (report.bag && report.bag->scans_integrated == 0) {
    const bag::BagRaysReport& b = *report.bag;
    printError("populate", "no cloud of " + options.input +
                               " could be mapped: " + std::to_string(b.clouds) + " clouds, " +
                               std::to_string(b.scans_no_pose) + " without a pose (poses from " +
                               b.pose_source + ": " + std::to_string(b.poses) + ")");
    return false;
  }
  if (report.rays.rays_accepted == 0) {
    char ranges[96];
    std::snprintf(ranges, sizeof(ranges), "--min-range %g m, --max-range %g m",
                  options.filter.min_range_m, options.filter.max_range_m);
    printError("populate", "no ray of " + options.input + " was integrated: " +
                               withCommas(report.rays.rays_in) + " in, all rejected (" +
                               rejectionsText(report.rays) + "; " + ranges + "): nothing written");
    return false;
  }
  return true;
}

/// Writes the map, the point cloud and the statistics to their staged names (a tiered map that
/// lost a region on the way writes no statistics and commits nothing); prints why not.
bool writeOutputs(const PopulateFlags& f, const VoxelMap& map, const PopulateReport& report,
                  const PopulateOptions& options, const PopulateTemps& temps) {
  if (!f.output.empty()) {
    if (auto ok = io::saveMap(map, temps.output); !ok) {
      printError("populate", "--output: " + ok.error().message);
      return false;
    }
  }
  if (!f.ply.empty()) {
    auto count = io::exportPly(map, io::ExportMode::kOccupied, temps.ply);
    if (!count) {
      printError("populate", "--ply: " + count.error().message);
      return false;
    }
  }
  if (auto ok = checkTiers(map); !ok) {
    printError("populate", ok.error().message);
    return false;
  }
  if (!f.stats_json.empty()) {
    const std::string json = dumpJson(statsJson(report, options));
    if (f.stats_json == "-") {
      std::printf("%s\n", json.c_str());
    } else if (auto ok = writeTextFile(temps.stats, json); !ok) {
      printError("populate", "--stats-json: " + ok.error().message);
      return false;
    }
  }
  return true;
}

int runPopulate(const PopulateFlags& f) {
  const char* command = "populate";
  auto options = toPopulateOptions(f.input, f.mapping);
  if (!options) {
    printError(command, options.error().message);
    return kExitUsage;
  }
  options->progress = !f.quiet;
  if (f.output.empty() && f.ply.empty() && f.stats_json.empty()) {
    printError(command,
               "nothing to write: give --output MAP, --ply CLOUD.ply or --stats-json FILE");
    return kExitUsage;
  }
  // Every output is staged under a temporary name now, so that an output that is an input or
  // cannot be written fails before minutes are spent on the input, and all are renamed at the
  // end: a run that fails part-way leaves none of them and existing files untouched.
  io::StagedOutputs staged(command);
  PopulateTemps temps;
  if (const int staged_code = stageOutputs(f, staged, temps); staged_code != kExitOk) {
    return staged_code;
  }
  // The spill file goes next to the first output (the user chose that disk for the map).
  const std::string& first_output =
      !f.output.empty() ? f.output : (!f.ply.empty() ? f.ply : f.stats_json);
  auto tiers = toTierConfig(f.mapping.tiers, first_output);
  if (!tiers) {
    printError(command, tiers.error().message);
    return kExitUsage;
  }
  options->map.tiers = *tiers;
  options->map.device_scan_marks = options->backend.name != "cpu";  // the CPU keeps bits
  const std::string pool_note = withCliFlags(mapper::fitPoolToMemory(options->map));
  if (!pool_note.empty() && !f.quiet) {
    std::fprintf(stderr, "raymap populate: note: %s\n", pool_note.c_str());
  }
  auto map = VoxelMap::create(options->map);
  if (!map) {
    printError(command, map.error().message);
    return kExitFailure;
  }
  auto report = populateFromFile(*map, *options);
  if (!report) {
    printError(command,
               report.error().message + bagDamageHint(bag::isBag(f.input), report.error()));
    if (!pool_note.empty()) {
      std::fprintf(stderr, "raymap populate: the pool was limited: %s\n", pool_note.c_str());
    }
    return kExitFailure;
  }
  printWarnings(*report, f.quiet);
  if (!somethingMapped(*report, *options) || !writeOutputs(f, *map, *report, *options, temps)) {
    return kExitFailure;
  }
  if (auto ok = staged.commit(); !ok) {
    printError(command, ok.error().message);
    return kExitFailure;
  }
  if (!f.quiet) {
    printSummary(*report, *options);
    if (!f.output.empty()) {
      std::printf("map file       %s\n", f.output.c_str());
    }
    if (!f.ply.empty()) {
      std::printf("point cloud    %s (occupied voxels at their voxel mean)\n", f.ply.c_str());
    }
  }
  return kExitOk;
}

}  // namespace

void printError(const std::string& command, const std::string& message) {
  std::fprintf(stderr, "raymap %s: error: %s\n", command.c_str(), withCliFlags(message).c_str());
}

std::string bagDamageHint(bool reads_bags, const Error& error) {
  if ((error.code != ErrorCode::kCorrupt && error.code != ErrorCode::kTruncated) || !reads_bags) {
    return {};
  }
  return " (--skip-damaged reads what the bag holds and says what was skipped)";
}

std::string withCommas(std::uint64_t value) {
  std::string digits = std::to_string(value);
  std::string out;
  const std::size_t n = digits.size();
  for (std::size_t i = 0; i < n; ++i) {
    out += digits[i];
    if ((n - i - 1) % 3 == 0 && i + 1 < n) {
      out += ',';
    }
  }
  return out;
}

void addPopulateCommand(CLI::App& app, int* exit_code) {
  auto flags = std::make_shared<PopulateFlags>();
  CLI::App* c = app.add_subcommand(
      "populate",
      "Build an occupancy or NDT map from a ray-cloud PLY or a point cloud + trajectory");
  c->add_option("input", flags->input, "Input file (.ply or .ply.gz)")->required();
  addMappingOptions(*c, flags->mapping);
  c->add_option("-o,--output", flags->output, "Map file to write (.rmap)");
  c->add_option("--ply", flags->ply, "Also write the occupied voxels as a point-cloud PLY");
  c->add_option("--stats-json", flags->stats_json, "Write run statistics as JSON ('-' = stdout)");
  c->add_flag("-q,--quiet", flags->quiet, "No progress bar and no summary");
  c->callback([flags, exit_code] { *exit_code = runPopulate(*flags); });
}

}  // namespace raymap::cli
