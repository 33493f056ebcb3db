// SPDX-License-Identifier: BSD-3-Clause
// `raymap export`: a map as a point cloud for any viewer.
#include <cstdio>
#include <memory>
#include <string>

#include "src/io/map_export.hpp"
#include "src/io/map_file.hpp"
#include "tools/raymap/cli_options.hpp"
#include "tools/raymap/commands.hpp"

namespace raymap::cli {
namespace {

struct ExportFlags {
  std::string map;
  std::string ply;
  std::string mode = "occupied";
  bool quiet = false;
};

int runExport(const ExportFlags& f) {
  auto mode = io::exportModeFromString(f.mode);
  if (!mode) {
    printError("export", mode.error().message);
    return kExitUsage;
  }
  if (auto ok = checkWritable(f.ply, "--ply"); !ok) {
    printError("export", ok.error().message);
    return kExitFailure;
  }
  auto map = io::loadMap(f.map);
  if (!map) {
    printError("export", map.error().message);
    return kExitFailure;
  }
  auto count = io::exportPly(*map, *mode, f.ply);
  if (!count) {
    printError("export", count.error().message);
    return kExitFailure;
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
  CLI::App* c = app.add_subcommand("export", "Write a map's voxels as a point-cloud PLY");
  c->add_option("map", flags->map, "Map file (.rmap)")->required();
  c->add_option("--ply", flags->ply, "Point cloud to write")->required();
  c->add_option("--mode", flags->mode,
                "occupied: occupied voxels at their voxel mean; free: free voxel centres; "
                "mean: every voxel with samples, at its mean")
      ->capture_default_str();
  c->add_flag("-q,--quiet", flags->quiet, "Print nothing on success");
  c->callback([flags, exit_code] { *exit_code = runExport(*flags); });
}

}  // namespace raymap::cli
