// SPDX-License-Identifier: BSD-3-Clause
// `raymap demo`: the whole offline job on built-in data, checked against the scene it came from.
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>
#include <optional>
#include <string>
#include <tuple>
#include <utility>

#include <sys/stat.h>
#include <unistd.h>

#include "platform/errno_text.hpp"
#include "src/heightmap/heightmap_generator.hpp"
#include "src/heightmap/heightmap_plan.hpp"
#include "src/io/heightmap_export.hpp"
#include "src/io/map_export.hpp"
#include "src/io/map_file.hpp"
#include "src/io/ray_cloud_writer.hpp"
#include "src/io/staged_outputs.hpp"
#include "src/sim/scene.hpp"
#include "src/sim/yard_scan.hpp"
#include "tools/raymap/commands.hpp"
#include "tools/raymap/populate.hpp"

namespace raymap::cli {
namespace {

struct DemoFlags {
  std::string output_dir = "raymap-demo";
  int scans = 10;
  unsigned threads = 0;
  bool quiet = false;
};

// The map must find at least this share of the true surface points and have at most this
// share of occupied voxels away from any surface; measured values are in docs/cli.md.
constexpr double kMinRecall = 0.95;
constexpr double kMinPrecision = 0.98;
/// Height-map surface cells within one voxel of the scene's true height (object edges, where
/// range noise puts a side's hits into the next column, make up the rest).
constexpr double kMinHeightAccuracy = 0.95;

/// The height map of the yard around the middle of the drive, checked against the scene's true
/// height field and written as a PNG.
struct HeightmapCheck {
  std::size_t surface_cells = 0;
  double accuracy = 0.0;  ///< fraction of surface cells within one voxel of the truth
  double milliseconds = 0.0;
};

Result<HeightmapCheck> heightmapOfYard(const VoxelMap& map, const sim::YardScanConfig& yard,
                                       const std::string& png) {
  heightmap::HeightmapOptions options;
  options.centre = {0.0, 0.0, 0.0};
  options.size = 20.0;
  heightmap::HeightmapPlan plan;
  if (auto ok = heightmap::planHeightmap(map, options, plan); !ok) {
    return Unexpected(ok.error());
  }
  heightmap::HeightMap result;
  const auto start = std::chrono::steady_clock::now();
  if (auto ok = heightmap::makeCpuHeightmapGenerator()->generate(map, plan, result); !ok) {
    return Unexpected(ok.error());
  }
  HeightmapCheck check;
  check.milliseconds =
      1e3 * std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (auto ok = io::writeHeightmapPng(png, result); !ok) {
    return Unexpected(ok.error());
  }
  sim::Scene scene;
  scene.boxes = yard.solids.empty() ? sim::yardSolids() : yard.solids;
  std::size_t right = 0;
  for (int j = 0; j < result.cells_y; ++j) {
    for (int i = 0; i < result.cells_x; ++i) {
      const std::size_t n = result.index(i, j);
      if (result.kind[n] != RM_HM_SURFACE) {
        continue;
      }
      ++check.surface_cells;
      const Vec3d c = result.cellCentre(i, j);
      const auto truth = sim::trueSurface(scene, c.x, c.y, options.centre.z, options.min_clearance);
      if (truth &&
          std::abs(truth->height - static_cast<double>(result.elevation[n])) <= result.resolution) {
        ++right;
      }
    }
  }
  check.accuracy = check.surface_cells > 0
                       ? static_cast<double>(right) / static_cast<double>(check.surface_cells)
                       : 0.0;
  return check;
}

struct SceneCheck {
  double recall = 0.0;     ///< true surface points with an occupied voxel within one voxel
  double precision = 0.0;  ///< occupied voxels whose centre is near a true surface
  int probe_failures = 0;  ///< places whose state the geometry fixes (shadows, solids)
};

SceneCheck checkAgainstScene(const VoxelMap& map, const sim::YardScanConfig& scene) {
  SceneCheck check;
  const double resolution = map.geometry().resolution;
  const std::vector<sim::Box> solids = sim::yardSolids();
  // Recall: the noiseless returns of the same scans lie exactly on the surfaces.
  sim::YardScanConfig truth = scene;
  truth.lidar.range_noise_m = 0.0;
  std::uint64_t points = 0;
  std::uint64_t found = 0;
  for (const Ray& ray : sim::simulateYardScans(truth)) {
    if ((ray.flags & kRayNoReturn) != 0u) {
      continue;
    }
    ++points;
    const Vec3i v = map.voxelOf(ray.sample);
    bool hit = false;
    for (int dz = -1; dz <= 1 && !hit; ++dz) {
      for (int dy = -1; dy <= 1 && !hit; ++dy) {
        for (int dx = -1; dx <= 1 && !hit; ++dx) {
          hit = map.state(v + Vec3i{dx, dy, dz}) == VoxelState::kOccupied;
        }
      }
    }
    found += hit ? 1u : 0u;
  }
  check.recall = points > 0 ? static_cast<double>(found) / static_cast<double>(points) : 0.0;
  // Precision: an occupied voxel is right when a surface passes within a voxel diagonal (plus
  // the range noise) of its centre.
  const double tolerance = std::sqrt(3.0) * 0.5 * resolution + 3.0 * scene.lidar.range_noise_m;
  std::uint64_t occupied = 0;
  std::uint64_t near_surface = 0;
  const int n = map.geometry().region_voxels;
  map.store().forEachRegion([&](std::uint32_t slot, Vec3i region) {
    for (int i = 0; i < n * n * n; ++i) {
      const Vec3i v = map.voxelAt(region, static_cast<std::uint32_t>(i));
      (void)slot;
      if (map.state(v) != VoxelState::kOccupied) {
        continue;
      }
      ++occupied;
      near_surface += sim::distanceToSurface(map.voxelCentre(v), solids) <= tolerance ? 1u : 0u;
    }
  });
  check.precision =
      occupied > 0 ? static_cast<double>(near_surface) / static_cast<double>(occupied) : 0.0;
  // Places the lidar cannot see stay unobserved.
  const Vec3d hidden[] = {{15.05, 0.05, 1.05},   // behind the east wall, below its top
                          {-6.45, 3.65, 0.55}};  // inside a crate
  for (const Vec3d& p : hidden) {
    if (map.state(map.voxelOf(p)) != VoxelState::kUnobserved) {
      ++check.probe_failures;
      std::fprintf(stderr, "demo check: (%.2f, %.2f, %.2f) should be unobserved\n", p.x, p.y, p.z);
    }
  }
  return check;
}

/// The demo's four files: where they go, and where they are staged until the end.
struct DemoFiles {
  std::string cloud, map, ply, png;
  std::string cloud_temp, map_temp, ply_temp, png_temp;
};

/// Stages the four files in `f.output_dir`. Prints the error and returns nothing when one
/// cannot be.
std::optional<DemoFiles> stageFiles(const DemoFlags& f, io::StagedOutputs& staged) {
  DemoFiles files;
  files.cloud = f.output_dir + "/yard_raycloud.ply";
  files.map = f.output_dir + "/yard.rmap";
  files.ply = f.output_dir + "/yard_occupied.ply";
  files.png = f.output_dir + "/yard_heightmap.png";
  for (const auto& [path, temp, what] :
       {std::tuple{&files.cloud, &files.cloud_temp, "the ray cloud"},
        {&files.map, &files.map_temp, "the map"},
        {&files.ply, &files.ply_temp, "the occupied voxels"},
        {&files.png, &files.png_temp, "the height map"}}) {
    auto staged_path = staged.add(*path, what);
    if (!staged_path) {
      printError("demo", staged_path.error().message);
      return std::nullopt;
    }
    *temp = std::move(*staged_path);
  }
  return files;
}

Expected<void, Error> writeRayCloud(const std::string& path, const std::vector<Ray>& rays) {
  auto writer = io::RayCloudWriter::open(path);
  if (!writer) {
    return Unexpected(writer.error());
  }
  if (auto ok = (*writer)->write(rays); !ok) {
    return ok;
  }
  return (*writer)->finish();
}

/// The recording mapped as `raymap populate` maps it, saved and exported.
struct MappedYard {
  PopulateReport report;
  std::uint64_t exported_points = 0;
};

/// Maps the staged ray cloud exactly as `raymap populate` does, saves the map and exports its
/// occupied voxels.
Result<MappedYard> mapYard(const DemoFlags& f, const DemoFiles& files) {
  PopulateOptions options;
  options.input = files.cloud_temp;
  options.backend.threads = f.threads;
  options.filter.max_range_m = 30.0;
  options.progress = !f.quiet;
  options.map.device_scan_marks = options.backend.name != "cpu";  // the CPU keeps bits
  auto map = VoxelMap::create(options.map);
  if (!map) {
    return Unexpected(map.error());
  }
  auto report = populateFromFile(*map, options);
  if (!report) {
    return Unexpected(report.error());
  }
  map->setInfo("source", files.cloud);  // the name the cloud will have, not its temporary one
  if (auto ok = io::saveMap(*map, files.map_temp); !ok) {
    return Unexpected(ok.error());
  }
  auto exported = io::exportPly(*map, io::ExportMode::kOccupied, files.ply_temp);
  if (!exported) {
    return Unexpected(exported.error());
  }
  return MappedYard{std::move(*report), *exported};
}

void printDemoSummary(const DemoFlags& f, const DemoFiles& files, std::size_t rays,
                      const MappedYard& mapped, const SceneCheck& check,
                      const HeightmapCheck& heights) {
  const PopulateReport& report = mapped.report;
  std::printf("simulated      %s rays in %d scans -> %s\n", withCommas(rays).c_str(), f.scans,
              files.cloud.c_str());
  std::printf("mapped         %s free, %s occupied voxels in %.3f s (%.3g M rays/s, %u threads)\n",
              withCommas(report.summary.voxels_free).c_str(),
              withCommas(report.summary.voxels_occupied).c_str(), report.integrate_seconds,
              static_cast<double>(report.rays.rays_accepted) / report.integrate_seconds / 1e6,
              report.threads);
  std::printf("wrote          %s, %s (%s points)\n", files.map.c_str(), files.ply.c_str(),
              withCommas(mapped.exported_points).c_str());
  std::printf(
      "checked        surface recall %.1f %% (>= %.0f %%), precision %.1f %% (>= %.0f %%),"
      " %d probe(s) wrong\n",
      100.0 * check.recall, 100.0 * kMinRecall, 100.0 * check.precision, 100.0 * kMinPrecision,
      check.probe_failures);
  std::printf(
      "height map     200 x 200 cells in %.1f ms, %s surface cells, %.1f %% within one voxel of "
      "the true height (>= %.0f %%) -> %s\n",
      heights.milliseconds, withCommas(heights.surface_cells).c_str(), 100.0 * heights.accuracy,
      100.0 * kMinHeightAccuracy, files.png.c_str());
  std::printf("next           raymap info %s\n", files.map.c_str());
  std::printf("               raymap heightmap %s --center 0,0,0 --png my.png\n",
              files.map.c_str());
  std::printf("               raymap populate %s --max-range 30 --output my.rmap\n",
              files.cloud.c_str());
}

/// The demo's work, its files staged in `staged` (renamed into place at the end, so a failure
/// leaves none of them). @return the exit code.
int demoInto(const DemoFlags& f, io::StagedOutputs& staged) {
  const char* command = "demo";
  const auto files = stageFiles(f, staged);
  if (!files) {
    return kExitFailure;
  }
  // 1. Simulate a lidar driving through the built-in yard and record it as a ray cloud.
  sim::YardScanConfig scene;
  scene.scans = f.scans;
  const std::vector<Ray> rays = sim::simulateYardScans(scene);
  if (auto ok = writeRayCloud(files->cloud_temp, rays); !ok) {
    printError(command, ok.error().message);
    return kExitFailure;
  }
  // 2. Map the recording exactly as `raymap populate` does (from the cloud's staged file).
  auto mapped = mapYard(f, *files);
  if (!mapped) {
    printError(command, mapped.error().message);
    return kExitFailure;
  }
  // 3. Check the map, read back from its file, against the scene it was made from.
  auto loaded = io::loadMap(files->map_temp);
  if (!loaded) {
    printError(command, loaded.error().message);
    return kExitFailure;
  }
  const SceneCheck check = checkAgainstScene(*loaded, scene);
  // 4. The height map a planner would get, against the scene's true height field.
  auto heights = heightmapOfYard(*loaded, scene, files->png_temp);
  if (!heights) {
    printError(command, heights.error().message);
    return kExitFailure;
  }
  // The files are complete: they are kept even when the check below fails (they are what to
  // look at then).
  if (auto ok = staged.commit(); !ok) {
    printError(command, ok.error().message);
    return kExitFailure;
  }
  if (!f.quiet) {
    printDemoSummary(f, *files, rays.size(), *mapped, check, *heights);
  }
  const bool passed = check.recall >= kMinRecall && check.precision >= kMinPrecision &&
                      check.probe_failures == 0 && heights->accuracy >= kMinHeightAccuracy;
  if (!passed) {
    printError(command, "the map does not match the simulated scene (see the check line)");
    return kExitFailure;
  }
  return kExitOk;
}

int runDemo(const DemoFlags& f) {
  const bool created = ::mkdir(f.output_dir.c_str(), 0755) == 0;
  if (!created && errno != EEXIST) {
    printError("demo", "cannot create '" + f.output_dir + "': " + platform::errnoText(errno));
    return kExitFailure;
  }
  int code = kExitFailure;
  {
    io::StagedOutputs staged("demo");
    code = demoInto(f, staged);
  }
  if (code != kExitOk && created) {
    ::rmdir(f.output_dir.c_str());  // a directory of this run's making, if it stayed empty
  }
  return code;
}

}  // namespace

void addDemoCommand(CLI::App& app, int* exit_code) {
  auto flags = std::make_shared<DemoFlags>();
  CLI::App* c = app.add_subcommand(
      "demo", "Simulate a lidar in a built-in yard, map it, save, export and check the map");
  c->add_option("--output-dir", flags->output_dir, "Where to write the files")
      ->capture_default_str();
  c->add_option("--scans", flags->scans, "Lidar scans to simulate")
      ->check(CLI::Range(1, 1000))
      ->capture_default_str();
  c->add_option("--threads", flags->threads, "Worker threads (0 = all cores)")
      ->capture_default_str();
  c->add_flag("-q,--quiet", flags->quiet, "Print nothing on success");
  c->callback([flags, exit_code] { *exit_code = runDemo(*flags); });
}

}  // namespace raymap::cli
