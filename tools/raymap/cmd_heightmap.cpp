// SPDX-License-Identifier: BSD-3-Clause
// `raymap heightmap`: the 2.5D height map of a map file around a position, as a PNG to look at
// and a CSV for machines.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "src/device/backend_choice.hpp"
#include "src/heightmap/heightmap_generator.hpp"
#include "src/heightmap/heightmap_plan.hpp"
#include "src/io/heightmap_export.hpp"
#include "src/io/map_file.hpp"
#include "src/io/staged_outputs.hpp"
#include "tools/raymap/cli_options.hpp"
#include "tools/raymap/commands.hpp"
#include "tools/raymap/json_output.hpp"
#include "tools/raymap/memory_tiers.hpp"
#include "tools/raymap/option_names.hpp"

namespace raymap::cli {
namespace {

struct HeightmapFlags {
  std::string map;
  std::string centre;
  double size = heightmap::HeightmapOptions::kDefaultSize;
  std::string mode = "planar";
  double min_clearance = heightmap::HeightmapOptions::kDefaultMinClearance;
  std::optional<double> floor_depth;
  std::optional<double> ceiling_height;
  bool virtual_surfaces = false;
  bool no_mean = false;
  std::string backend = "cpu";
  std::string opencl_platform;
  std::string opencl_device;
  int cuda_device = 0;
  std::string fallback = "none";
  std::string png;
  std::string csv;
  int repeat = 1;
  bool json = false;
  bool quiet = false;
  std::string max_memory = "4GiB";  ///< a larger map streams through the tiers
  TierFlags tiers;
};

/// Default centre: the middle of the observed area, at the lowest observed height (the ground of
/// a single-storey map).
Vec3d defaultCentre(const VoxelMap& map) {
  const MapSummary s = map.summarise();
  return {0.5 * (s.observed_min.x + s.observed_max.x), 0.5 * (s.observed_min.y + s.observed_max.y),
          s.observed_min.z + 0.5 * map.geometry().resolution};
}

std::string threeDecimals(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.3f", value);
  return text;
}

/// The cells of a height map by kind, the surface's elevation range and (NDT maps) the surface
/// cells with a valid normal.
struct CellCounts {
  std::uint64_t kinds[4] = {};
  float lowest = INFINITY;
  float highest = -INFINITY;
  std::uint64_t normal_cells = 0;
};

CellCounts countCells(const heightmap::HeightMap& result) {
  CellCounts c;
  for (std::size_t n = 0; n < result.cellCount(); ++n) {
    if (result.has_normals && !std::isnan(result.normal_z[n])) {
      ++c.normal_cells;
    }
    c.kinds[std::min<std::uint32_t>(result.kind[n], 3)] += 1;
    if (result.kind[n] == RM_HM_SURFACE) {
      c.lowest = std::min(c.lowest, result.elevation[n]);
      c.highest = std::max(c.highest, result.elevation[n]);
    }
  }
  return c;
}

/// What one run made and how long it took (sorted generation times, seconds).
struct HeightmapRun {
  heightmap::HeightmapOptions options;
  heightmap::HeightMap result;
  std::vector<double> seconds;
  std::string backend;
  std::string device;
};

void printJson(const HeightmapFlags& f, const HeightmapRun& run) {
  const heightmap::HeightMap& result = run.result;
  const CellCounts c = countCells(result);
  Json j = {
      {"map", f.map},
      {"backend", run.backend},
      {"device", run.device},
      {"mode", heightmap::toString(run.options.mode)},
      {"cells_x", result.cells_x},
      {"cells_y", result.cells_y},
      {"resolution_m", result.resolution},
      {"centre_x_m", result.centre_x},
      {"centre_y_m", result.centre_y},
      {"reference_z_m", result.reference_z},
      {"min_clearance_m", run.options.min_clearance},
      {"surface_cells", c.kinds[RM_HM_SURFACE]},
      {"virtual_cells", c.kinds[RM_HM_VIRTUAL]},
      {"vacant_cells", c.kinds[RM_HM_VACANT]},
      {"unknown_cells", c.kinds[RM_HM_UNKNOWN]},
      {"repeat", f.repeat},
      {"seconds_min", run.seconds.front()},
      {"seconds_median", run.seconds[run.seconds.size() / 2]},
  };
  if (c.kinds[RM_HM_SURFACE] > 0) {
    j["elevation_min_m"] = c.lowest;
    j["elevation_max_m"] = c.highest;
  }
  if (result.has_normals) {
    j["normal_cells"] = c.normal_cells;
  }
  std::printf("%s\n", dumpJson(j).c_str());
}

void printText(const HeightmapFlags& f, const HeightmapRun& run) {
  const heightmap::HeightMap& result = run.result;
  const CellCounts c = countCells(result);
  std::printf(
      "height map %d x %d cells at %s m around (%s, %s), reference z %s m, %s mode: "
      "%s surface, %s virtual, %s vacant, %s unknown",
      result.cells_x, result.cells_y, threeDecimals(result.resolution).c_str(),
      threeDecimals(result.centre_x).c_str(), threeDecimals(result.centre_y).c_str(),
      threeDecimals(result.reference_z).c_str(),
      std::string(heightmap::toString(run.options.mode)).c_str(),
      withCommas(c.kinds[RM_HM_SURFACE]).c_str(), withCommas(c.kinds[RM_HM_VIRTUAL]).c_str(),
      withCommas(c.kinds[RM_HM_VACANT]).c_str(), withCommas(c.kinds[RM_HM_UNKNOWN]).c_str());
  if (c.kinds[RM_HM_SURFACE] > 0) {
    std::printf("; elevation %s .. %s m", threeDecimals(static_cast<double>(c.lowest)).c_str(),
                threeDecimals(static_cast<double>(c.highest)).c_str());
  }
  if (result.has_normals) {
    std::printf("; %s with normals", withCommas(c.normal_cells).c_str());
  }
  std::printf("\ngenerated in %.2f ms on %s%s\n", 1e3 * run.seconds[run.seconds.size() / 2],
              run.device.c_str(), f.repeat > 1 ? " (median)" : "");
  for (const auto& [path, what] : {std::pair{f.png, "image"}, std::pair{f.csv, "cells"}}) {
    if (!path.empty()) {
      std::printf("wrote %s (%s)\n", path.c_str(), what);
    }
  }
}

/// The height-map options the flags ask for around the map (the default centre from it); prints
/// why not.
std::optional<heightmap::HeightmapOptions> toHeightmapOptions(const HeightmapFlags& f,
                                                              const VoxelMap& map) {
  heightmap::HeightmapOptions options;
  options.mode =
      f.mode == "fill" ? heightmap::HeightmapMode::kFill : heightmap::HeightmapMode::kPlanar;
  if (f.centre.empty()) {
    options.centre = defaultCentre(map);
  } else {
    auto centre = parseVector(f.centre, "--center");
    if (!centre) {
      printError("heightmap", centre.error().message);
      return std::nullopt;
    }
    options.centre = *centre;
  }
  options.size = f.size;
  options.min_clearance = f.min_clearance;
  options.floor_depth = f.floor_depth;
  options.ceiling_height = f.ceiling_height;
  options.virtual_surfaces = f.virtual_surfaces;
  options.use_voxel_mean = !f.no_mean;
  return options;
}

/// Makes the generator the flags ask for and generates `repeat` times, timing each; prints why
/// not.
bool generate(const HeightmapFlags& f, const VoxelMap& map, const heightmap::HeightmapPlan& plan,
              HeightmapRun& run) {
  BackendChoice choice;
  choice.name = f.backend;
  choice.opencl_platform = f.opencl_platform;
  choice.opencl_device = f.opencl_device;
  choice.cuda_device = f.cuda_device;
  choice.fallback_cpu = f.fallback == "cpu";
  auto created = createHeightmapGenerator(choice);
  if (!created) {
    printError("heightmap", created.error().message);
    return false;
  }
  if (!created->fallback_warning.empty()) {
    std::fprintf(stderr, "raymap heightmap: warning: %s\n",
                 withCliFlags(created->fallback_warning).c_str());
  }
  heightmap::HeightmapGenerator& generator = *created->generator;
  run.backend = generator.name();
  run.device = generator.deviceName();
  for (int r = 0; r < f.repeat; ++r) {
    const auto start = std::chrono::steady_clock::now();
    if (auto ok = generator.generate(map, plan, run.result); !ok) {
      printError("heightmap", ok.error().message);
      return false;
    }
    run.seconds.push_back(
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  }
  std::sort(run.seconds.begin(), run.seconds.end());
  return true;
}

/// Writes the staged outputs and puts them in place (a tiered map that lost a region on the way
/// commits nothing); prints why not.
bool writeOutputs(const HeightmapFlags& f, const VoxelMap& map, const heightmap::HeightMap& result,
                  io::StagedOutputs& staged, const std::string& png_temp,
                  const std::string& csv_temp) {
  if (!f.png.empty()) {
    if (auto ok = io::writeHeightmapPng(png_temp, result); !ok) {
      printError("heightmap", "--png: " + ok.error().message);
      return false;
    }
  }
  if (!f.csv.empty()) {
    if (auto ok = io::writeHeightmapCsv(csv_temp, result); !ok) {
      printError("heightmap", "--csv: " + ok.error().message);
      return false;
    }
  }
  if (auto ok = checkTiers(map); !ok) {
    printError("heightmap", ok.error().message);
    return false;
  }
  if (auto ok = staged.commit(); !ok) {
    printError("heightmap", ok.error().message);
    return false;
  }
  return true;
}

int runHeightmap(const HeightmapFlags& f) {
  if (f.mode != "planar" && f.mode != "fill") {
    printError("heightmap", "--mode " + f.mode + ": must be planar or fill");
    return kExitUsage;
  }
  if (f.repeat < 1) {
    printError("heightmap", "--repeat: must be at least 1");
    return kExitUsage;
  }
  // Both files are staged now (an unwritable one fails before the work) and renamed together
  // at the end: a failure leaves neither.
  io::StagedOutputs staged("heightmap");
  staged.input(f.map, "the map");
  std::string png_temp;
  std::string csv_temp;
  for (const auto& [path, option, temp] :
       {std::tuple{&f.png, "--png", &png_temp}, std::tuple{&f.csv, "--csv", &csv_temp}}) {
    if (!path->empty()) {
      auto staged_path = staged.add(*path, option);
      if (!staged_path) {
        printError("heightmap", staged_path.error().message);
        return exitCodeFor(staged_path.error());
      }
      *temp = std::move(*staged_path);
    }
  }
  auto load = toLoadOptions(f.max_memory, f.tiers, !f.png.empty() ? f.png : f.csv);
  if (!load) {
    printError("heightmap", load.error().message);
    return kExitUsage;
  }
  auto map = io::loadMap(f.map, *load);
  if (!map) {
    printError("heightmap", map.error().message);
    return kExitFailure;
  }
  HeightmapRun run;
  const auto options = toHeightmapOptions(f, *map);
  if (!options) {
    return kExitUsage;
  }
  run.options = *options;
  heightmap::HeightmapPlan plan;
  if (auto ok = heightmap::planHeightmap(*map, run.options, plan); !ok) {
    printError("heightmap", f.map + ": " + ok.error().message);
    return kExitFailure;
  }
  if (!generate(f, *map, plan, run) ||
      !writeOutputs(f, *map, run.result, staged, png_temp, csv_temp)) {
    return kExitFailure;
  }
  if (f.json) {
    printJson(f, run);
  } else if (!f.quiet) {
    printText(f, run);
  }
  return kExitOk;
}

}  // namespace

void addHeightmapCommand(CLI::App& app, int* exit_code) {
  auto f = std::make_shared<HeightmapFlags>();
  CLI::App* c = app.add_subcommand(
      "heightmap", "The 2.5D height map of a map around a position (PNG to look at, CSV)");
  c->add_option("map", f->map, "Map file (.rmap)")->required();
  c->add_option("--center,--centre", f->centre,
                "X,Y,Z metres: the map's centre column and the reference height surfaces are "
                "searched around (default: the middle of the observed area at its lowest "
                "observed height)");
  c->add_option("--size", f->size, "Side of the square map and of the searched cube, metres")
      ->capture_default_str();
  c->add_option("--mode", f->mode,
                "planar: one reference height for all columns; fill: flood fill from the centre, "
                "each column searching around its neighbour's height (follows stairs and ramps)")
      ->capture_default_str();
  c->add_option("--min-clearance", f->min_clearance,
                "Free height a surface needs above it, metres (the robot's height)")
      ->capture_default_str();
  c->add_option("--floor", f->floor_depth,
                "Metres searched below a column's reference (default: size / 2)");
  c->add_option("--ceiling", f->ceiling_height,
                "Metres searched above a column's reference (default: size / 2)");
  c->add_flag("--virtual-surfaces", f->virtual_surfaces,
              "Report virtual surfaces: free space seen over unseen space (ditch, drop-off)");
  c->add_flag("--no-voxel-mean", f->no_mean, "Use voxel centres, not voxel means, for heights");
  c->add_option("--backend", f->backend, "cpu, opencl or cuda")->capture_default_str();
  c->add_option("--opencl-platform", f->opencl_platform, "OpenCL platform: index or name part");
  c->add_option("--opencl-device", f->opencl_device, "OpenCL device: index or name part");
  c->add_option("--cuda-device", f->cuda_device, "CUDA device ordinal")->capture_default_str();
  c->add_option("--fallback", f->fallback, "none, or cpu: generate on the CPU if the device fails")
      ->check(CLI::IsMember({"none", "cpu"}))
      ->capture_default_str();
  c->add_option("--png", f->png, "Write a colour-mapped image with a legend and scale bar");
  c->add_option("--csv", f->csv, "Write x,y,elevation,clearance,kind per cell");
  c->add_option("--repeat", f->repeat, "Generate N times and report the median time (timing)")
      ->capture_default_str();
  c->add_flag("--json", f->json, "Print a JSON summary");
  c->add_flag("-q,--quiet", f->quiet, "Print nothing on success");
  addMaxMemoryOption(*c, f->max_memory);
  addTierOptions(*c, f->tiers);
  c->callback([f, exit_code] { *exit_code = runHeightmap(*f); });
}

}  // namespace raymap::cli
