// SPDX-License-Identifier: BSD-3-Clause
// `raymap export`: a map as a point cloud for any viewer.
#include <cstdio>
#include <memory>
#include <optional>
#include <string>
#include <utility>

#include "raymap/export.hpp"

#include "src/io/map_exports.hpp"
#include "src/io/map_file.hpp"
#include "src/io/ndt_export.hpp"
#include "src/io/staged_outputs.hpp"
#include "tools/raymap/cli_options.hpp"
#include "tools/raymap/commands.hpp"
#include "tools/raymap/memory_tiers.hpp"

namespace raymap::cli {
namespace {

struct ExportFlags {
  std::string map;
  std::string ply;
  std::string mode = "occupied";
  std::optional<double> sigmas;
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
std::optional<VoxelMap> openMapForExport(const ExportFlags& f, io::StagedOutputs& staged,
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
int commitExport(io::StagedOutputs& staged, const VoxelMap& map) {
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

/// The request the flags ask for; prints why not (naming the flag) and returns nullopt.
std::optional<ExportRequest> toExportRequest(const ExportFlags& f) {
  ExportRequest request;
  const auto kind = exportKindFromName(f.mode);
  if (!kind) {
    printError("export", "--mode: unknown mode '" + f.mode +
                             "' (expected occupied, free, mean, decay, ndt, ndt-points, tsdf or "
                             "tsdf-mesh)");
    return std::nullopt;
  }
  request.kind = *kind;
  request.decay_threshold = f.threshold;
  request.ndt_sigmas = f.sigmas;
  request.ndt_min_axis = f.min_axis;
  request.tsdf_min_weight = f.min_weight;
  if (f.colour) {
    request.ndt_colour = exportColourFromName(*f.colour);
    if (!request.ndt_colour) {
      printError("export", "--colour: unknown colour '" + *f.colour +
                               "' (expected height, intensity or permeability)");
      return std::nullopt;
    }
  }
  if (auto ok = io::validateExportRequest(request); !ok) {
    printError("export", ok.error().message);
    return std::nullopt;
  }
  return request;
}

/// What an export wrote, as one line.
void printWritten(const ExportFlags& f, const ExportRequest& r, const ExportCounts& counts) {
  const std::string items = withCommas(counts.items);
  const char* ply = f.ply.c_str();
  const std::string colour(toString(r.ndt_colour.value_or(ExportColour::kHeight)));
  switch (r.kind) {
    case ExportKind::kNdt:
      std::printf("wrote %s NDT ellipsoids (%g sigma, coloured by %s) to %s\n", items.c_str(),
                  r.ndt_sigmas.value_or(io::NdtExportOptions::kDefaultSigmas), colour.c_str(), ply);
      return;
    case ExportKind::kNdtPoints:
      std::printf("wrote %s NDT means with normals (coloured by %s) to %s\n", items.c_str(),
                  colour.c_str(), ply);
      return;
    case ExportKind::kTsdf:
      std::printf("wrote %s TSDF surface points (zero crossings, weight >= %g) to %s\n",
                  items.c_str(), r.tsdf_min_weight.value_or(kDefaultTsdfMinWeight), ply);
      return;
    case ExportKind::kTsdfMesh:
      std::printf(
          "wrote a TSDF surface mesh of %s triangles, %s vertices (marching cubes, "
          "weight >= %g) to %s\n",
          items.c_str(), withCommas(counts.vertices).c_str(),
          r.tsdf_min_weight.value_or(kDefaultTsdfMinWeight), ply);
      return;
    case ExportKind::kOccupied:
    case ExportKind::kFree:
    case ExportKind::kMean:
    case ExportKind::kDecay:
      break;
  }
  std::printf("wrote %s points (%s) to %s\n", items.c_str(), f.mode.c_str(), ply);
}

int runExport(const ExportFlags& f) {
  const auto request = toExportRequest(f);
  if (!request) {
    return kExitUsage;
  }
  io::StagedOutputs staged("export");
  std::string ply;
  int exit_code = kExitOk;
  auto map = openMapForExport(f, staged, &ply, &exit_code);
  if (!map) {
    return exit_code;
  }
  auto counts = io::exportMap(*map, *request, ply);
  if (!counts) {
    printError("export", f.map + ": " + counts.error().message);
    return kExitFailure;
  }
  if (const int committed = commitExport(staged, *map); committed != kExitOk) {
    return committed;
  }
  if (!f.quiet) {
    printWritten(f, *request, *counts);
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
  c->add_option("--sigmas", flags->sigmas,
                "NDT: ellipsoid half-axes in standard deviations (default 2)");
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
