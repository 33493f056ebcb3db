// SPDX-License-Identifier: BSD-3-Clause
// `raymap export`: a map as a point cloud for any viewer.
#include <cmath>
#include <cstdio>
#include <memory>
#include <optional>
#include <string>
#include <utility>

#include "src/io/map_export.hpp"
#include "src/io/map_file.hpp"
#include "src/io/ndt_export.hpp"
#include "src/io/tsdf_export.hpp"
#include "tools/raymap/cli_options.hpp"
#include "tools/raymap/commands.hpp"
#include "tools/raymap/memory_tiers.hpp"
#include "tools/raymap/staged_outputs.hpp"

namespace raymap::cli {
namespace {

// tsdf, tsdf-mesh: crossings between voxels with at least this many rays' weight by default.
constexpr double kDefaultTsdfMinWeight = 1.0;

struct ExportFlags {
  std::string map;
  std::string ply;
  std::string mode = "occupied";
  double sigmas = io::NdtExportOptions::kDefaultSigmas;
  std::optional<double> min_axis;
  std::optional<std::string> colour;
  std::optional<double> threshold;   ///< decay: lowest rate exported, per metre
  std::optional<double> min_weight;  ///< tsdf, tsdf-mesh: lightest voxel exported
  bool quiet = false;
  std::string max_memory = "4GiB";  ///< a larger map streams through the tiers
  TierFlags tiers;
};

/// Stages --ply (refused when it is the map, failing when it cannot be written), then loads the
/// map; prints why not and returns nullopt. `*ply_temp` is the name to write the PLY to.
std::optional<VoxelMap> openMapForExport(const ExportFlags& f, StagedOutputs& staged,
                                         std::string* ply_temp, int* exit_code) {
  staged.input(f.map, "the map");
  auto temp = staged.add(f.ply, "--ply");
  if (!temp) {
    printError("export", temp.error().message);
    *exit_code = exitCodeFor(temp.error());
    return std::nullopt;
  }
  *ply_temp = std::move(*temp);
  auto load = toLoadOptions(f.max_memory, f.tiers, f.ply);
  if (!load) {
    printError("export", load.error().message);
    *exit_code = kExitUsage;
    return std::nullopt;
  }
  auto map = io::loadMap(f.map, *load);
  if (!map) {
    printError("export", map.error().message);
    *exit_code = kExitFailure;
    return std::nullopt;
  }
  return std::move(*map);
}

/// Puts the written PLY in place; prints why not. A tiered map that could not read a region back
/// (a damaged spill file) wrote an incomplete PLY: it is not committed. @return the exit code.
int commitExport(StagedOutputs& staged, const VoxelMap& map) {
  if (auto ok = checkTiers(map); !ok) {
    printError("export", ok.error().message);
    return kExitFailure;
  }
  if (auto ok = staged.commit(); !ok) {
    printError("export", ok.error().message);
    return kExitFailure;
  }
  return kExitOk;
}

int runNdtExport(const ExportFlags& f) {
  const char* command = "export";
  io::NdtExportOptions options;
  options.sigmas = f.sigmas;
  options.min_axis_m = f.min_axis;
  if (f.colour) {
    auto colour = io::ndtColourFromString(*f.colour);
    if (!colour) {
      printError(command, "--colour: " + colour.error().message);
      return kExitUsage;
    }
    options.colour = *colour;
  }
  if (auto ok = options.validate(); !ok) {
    printError(command, ok.error().message);
    return kExitUsage;
  }
  StagedOutputs staged(command);
  std::string ply;
  int exit_code = kExitOk;
  auto map = openMapForExport(f, staged, &ply, &exit_code);
  if (!map) {
    return exit_code;
  }
  const bool points = f.mode == "ndt-points";
  auto count = points ? io::exportNdtPoints(*map, options, ply)
                      : io::exportNdtEllipsoids(*map, options, ply);
  if (!count) {
    printError(command, f.map + ": " + count.error().message);
    return kExitFailure;
  }
  if (const int committed = commitExport(staged, *map); committed != kExitOk) {
    return committed;
  }
  if (!f.quiet) {
    if (points) {
      std::printf("wrote %s NDT means with normals (coloured by %s) to %s\n",
                  withCommas(*count).c_str(), io::toString(options.colour), f.ply.c_str());
    } else {
      std::printf("wrote %s NDT ellipsoids (%g sigma, coloured by %s) to %s\n",
                  withCommas(*count).c_str(), options.sigmas, io::toString(options.colour),
                  f.ply.c_str());
    }
  }
  return kExitOk;
}

int runTsdfExport(const ExportFlags& f) {
  const char* command = "export";
  const double min_weight = f.min_weight.value_or(kDefaultTsdfMinWeight);
  if (!std::isfinite(min_weight) || min_weight < 0.0) {
    printError(command, "--min-weight: must be a finite weight >= 0 (rays)");
    return kExitUsage;
  }
  StagedOutputs staged(command);
  std::string ply;
  int exit_code = kExitOk;
  auto map = openMapForExport(f, staged, &ply, &exit_code);
  if (!map) {
    return exit_code;
  }
  if (f.mode == "tsdf-mesh") {
    auto counts = io::exportTsdfMesh(*map, ply, min_weight);
    if (!counts) {
      printError(command, f.map + ": " + counts.error().message);
      return kExitFailure;
    }
    if (const int committed = commitExport(staged, *map); committed != kExitOk) {
      return committed;
    }
    if (!f.quiet) {
      std::printf(
          "wrote a TSDF surface mesh of %s triangles, %s vertices (marching cubes, "
          "weight >= %g) to %s\n",
          withCommas(counts->triangles).c_str(), withCommas(counts->vertices).c_str(), min_weight,
          f.ply.c_str());
    }
    return kExitOk;
  }
  auto count = io::exportTsdfSurface(*map, ply, min_weight);
  if (!count) {
    printError(command, f.map + ": " + count.error().message);
    return kExitFailure;
  }
  if (const int committed = commitExport(staged, *map); committed != kExitOk) {
    return committed;
  }
  if (!f.quiet) {
    std::printf("wrote %s TSDF surface points (zero crossings, weight >= %g) to %s\n",
                withCommas(*count).c_str(), min_weight, f.ply.c_str());
  }
  return kExitOk;
}

int runExport(const ExportFlags& f) {
  if (f.mode == "ndt" || f.mode == "ndt-points") {
    return runNdtExport(f);
  }
  const bool tsdf = f.mode == "tsdf" || f.mode == "tsdf-mesh";
  if (f.min_weight && !tsdf) {
    printError("export", "--min-weight applies only to --mode tsdf or tsdf-mesh");
    return kExitUsage;
  }
  if (tsdf) {
    if (f.threshold || f.colour || f.min_axis || f.sigmas != io::NdtExportOptions::kDefaultSigmas) {
      const std::string options = "--threshold, --colour, --sigmas and --min-axis";
      printError("export",
                 options + " do not apply to --mode " + f.mode + " (its option is --min-weight)");
      return kExitUsage;
    }
    return runTsdfExport(f);
  }
  if (f.colour || f.min_axis || f.sigmas != io::NdtExportOptions::kDefaultSigmas) {
    printError("export",
               "--colour, --sigmas and --min-axis apply only to --mode ndt or ndt-points");
    return kExitUsage;
  }
  auto mode = io::exportModeFromString(f.mode);
  if (!mode) {
    printError("export", "--mode: unknown mode '" + f.mode +
                             "' (expected occupied, free, mean, decay, ndt, ndt-points, tsdf or "
                             "tsdf-mesh)");
    return kExitUsage;
  }
  io::ExportOptions options;
  if (f.threshold) {
    if (*mode != io::ExportMode::kDecay) {
      printError("export", "--threshold applies only to --mode decay");
      return kExitUsage;
    }
    if (!std::isfinite(*f.threshold) || *f.threshold < 0.0) {
      printError("export", "--threshold: must be a finite rate >= 0 (reflections per metre)");
      return kExitUsage;
    }
    options.decay_threshold = *f.threshold;
  }
  StagedOutputs staged("export");
  std::string ply;
  int exit_code = kExitOk;
  auto map = openMapForExport(f, staged, &ply, &exit_code);
  if (!map) {
    return exit_code;
  }
  auto count = io::exportPly(*map, *mode, ply, options);
  if (!count) {
    printError("export", f.map + ": " + count.error().message);
    return kExitFailure;
  }
  if (const int committed = commitExport(staged, *map); committed != kExitOk) {
    return committed;
  }
  if (!f.quiet) {
    std::printf("wrote %s points (%s) to %s\n", withCommas(*count).c_str(), f.mode.c_str(),
                f.ply.c_str());
  }
  return kExitOk;
}

}  // namespace

void addExportCommand(CLI::App& app, int* exit_code) {
  auto flags = std::make_shared<ExportFlags>();
  CLI::App* c = app.add_subcommand(
      "export",
      "Write a map's voxels as a point-cloud PLY, its NDT Gaussians as ellipsoids, or its TSDF "
      "surface as points or a triangle mesh");
  c->add_option("map", flags->map, "Map file (.rmap)")->required();
  c->add_option("--ply", flags->ply, "PLY file to write")->required();
  c->add_option(
       "--mode", flags->mode,
       "occupied: occupied voxels at their voxel mean; free: free voxel centres; "
       "mean: every voxel with samples, at its mean; decay: every voxel of a decay-rate map "
       "whose rate (samples per metre of ray path) is at least --threshold; ndt: a "
       "triangle-mesh ellipsoid per occupied NDT Gaussian; ndt-points: the Gaussians' "
       "means with normals; tsdf: the zero crossings of a TSDF map (its surface) as points "
       "with normals; tsdf-mesh: that surface as a triangle mesh (marching cubes)")
      ->capture_default_str();
  c->add_option("--sigmas", flags->sigmas, "NDT: ellipsoid half-axes in standard deviations")
      ->capture_default_str();
  c->add_option("--min-axis", flags->min_axis,
                "NDT: smallest ellipsoid half-axis, metres (default 0.05 voxel edges), so flat "
                "surfels stay visible");
  c->add_option("--colour", flags->colour,
                "NDT: height (default), or for ndt-tm maps intensity or permeability; blue (low) "
                "- cyan - green - yellow - red (high)");
  c->add_option("--threshold", flags->threshold,
                "decay: the lowest decay rate exported, reflections per metre (default 0: every "
                "voxel a ray entered)");
  c->add_option("--min-weight", flags->min_weight,
                "tsdf: leave out crossings between voxels lighter than this; tsdf-mesh: leave out "
                "cubes with a voxel lighter than this; rays (default 1)");
  c->add_flag("-q,--quiet", flags->quiet, "Print nothing on success");
  addMaxMemoryOption(*c, flags->max_memory);
  addTierOptions(*c, flags->tiers);
  c->callback([flags, exit_code] { *exit_code = runExport(*flags); });
}

}  // namespace raymap::cli
