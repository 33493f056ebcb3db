// SPDX-License-Identifier: BSD-3-Clause
// `raymap simulate`: a recording of a scene file's sensors (a lidar, depth cameras), as a ray
// cloud or (lidar) a point cloud with its trajectory, and the scene's true height field.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "src/core/eigen_conversions.hpp"
#include "src/io/ray_cloud_writer.hpp"
#include "src/io/staged_outputs.hpp"
#include "src/io/trajectory.hpp"
#include "src/sim/scene_file.hpp"
#include "src/sim/scene_recording.hpp"
#include "tools/raymap/cli_options.hpp"
#include "tools/raymap/commands.hpp"

namespace raymap::cli {
namespace {

/// The height-map generator's default clearance, so the truth matches what it looks for.
constexpr double kDefaultMinClearance = 0.5;
constexpr double kDefaultTruthResolution = 0.1;

struct SimulateFlags {
  std::string scene;
  std::string rays;
  std::string points;
  std::string trajectory;
  std::string truth;
  double truth_resolution = kDefaultTruthResolution;
  std::string truth_box;
  std::optional<double> truth_reference;
  double min_clearance = kDefaultMinClearance;
  std::optional<std::uint64_t> seed;
  std::optional<int> scans;
  std::vector<std::string> sensors;  ///< lidar, depth; empty = every sensor the scene has
  bool quiet = false;
};

/// The xy rectangle of the truth grid.
struct Rect {
  double x_min = 0.0;
  double y_min = 0.0;
  double x_max = 0.0;
  double y_max = 0.0;
};

/// "xmin,ymin,xmax,ymax" with min < max.
Result<Rect> parseRect(const std::string& text, const std::string& option) {
  std::vector<double> values;
  std::stringstream in(text);
  std::string part;
  while (std::getline(in, part, ',')) {
    char* end = nullptr;
    const double value = std::strtod(part.c_str(), &end);
    if (part.empty() || end != part.c_str() + part.size() || !std::isfinite(value)) {
      values.clear();
      break;
    }
    values.push_back(value);
  }
  if (values.size() != 4 || !(values[0] < values[2]) || !(values[1] < values[3])) {
    return fail(ErrorCode::kInvalidArgument,
                option + ": '" + text + "' is not xmin,ymin,xmax,ymax with min < max (metres)");
  }
  return Rect{values[0], values[1], values[2], values[3]};
}

/// The xy bounds of the scene's objects and the sensor path.
Rect sceneRect(const sim::Scene& scene, const sim::SensorPath& path) {
  const sim::SensorPose& start = path.knots().front();
  Rect rect{start.position.x, start.position.y, start.position.x, start.position.y};
  const auto add = [&rect](double x, double y) {
    rect = {std::min(rect.x_min, x), std::min(rect.y_min, y), std::max(rect.x_max, x),
            std::max(rect.y_max, y)};
  };
  for (const sim::SensorPose& knot : path.knots()) {
    add(knot.position.x, knot.position.y);
  }
  if (const std::optional<sim::Box> bounds = sim::objectBounds(scene)) {
    add(bounds->min.x, bounds->min.y);
    add(bounds->max.x, bounds->max.y);
  }
  return rect;
}

/// Rotation about +z by `yaw` as a unit quaternion.
Eigen::Quaterniond yawQuaternion(double yaw_rad) {
  return Eigen::Quaterniond(Eigen::AngleAxisd(yaw_rad, Eigen::Vector3d::UnitZ()));
}

/// The true height field as CSV text: one row per cell of the map's grid (faces on multiples of
/// the resolution) that overlaps `box`, rows by increasing y, then x. Returns the cell count.
std::uint64_t truthCsv(const sim::Scene& scene, const Rect& box, double resolution,
                       double reference_z, double min_clearance, std::string& csv) {
  // A hair of slack so that a box edge on a cell face does not add a cell beyond it.
  constexpr double kSlack = 1e-9;
  const auto first = [&](double v) {
    return static_cast<long>(std::floor(v / resolution + kSlack));
  };
  const auto last = [&](double v) {
    return static_cast<long>(std::ceil(v / resolution - kSlack)) - 1;
  };
  csv = "x,y,height,clearance\n";
  std::uint64_t cells = 0;
  char line[128];
  for (long j = first(box.y_min); j <= last(box.y_max); ++j) {
    const double y = (static_cast<double>(j) + 0.5) * resolution;
    for (long i = first(box.x_min); i <= last(box.x_max); ++i) {
      const double x = (static_cast<double>(i) + 0.5) * resolution;
      const std::optional<sim::TrueSurface> surface =
          sim::trueSurface(scene, x, y, reference_z, min_clearance);
      int n = std::snprintf(line, sizeof(line), "%.10g,%.10g,", x, y);
      if (surface) {
        n += std::isinf(surface->clearance)
                 ? std::snprintf(line + n, sizeof(line) - static_cast<std::size_t>(n), "%.10g,inf",
                                 surface->height)
                 : std::snprintf(line + n, sizeof(line) - static_cast<std::size_t>(n),
                                 "%.10g,%.10g", surface->height, surface->clearance);
      } else {
        n += std::snprintf(line + n, sizeof(line) - static_cast<std::size_t>(n), ",");
      }
      csv.append(line, static_cast<std::size_t>(n));
      csv += '\n';
      ++cells;
    }
  }
  return cells;
}

/// Writes the rays as a PLY; returns the vertex count.
Result<std::uint64_t> writeRays(const std::vector<Ray>& rays, const std::string& path,
                                io::PlyLayout layout) {
  auto writer = io::RayCloudWriter::open(path, layout);
  if (!writer) {
    return Unexpected(writer.error());
  }
  if (auto ok = (*writer)->write(rays); !ok) {
    return Unexpected(ok.error());
  }
  if (auto ok = (*writer)->finish(); !ok) {
    return Unexpected(ok.error());
  }
  return (*writer)->count();
}

/// The sensor pose of every column, as `time x y z qw qx qy qz` lines.
Expected<void, Error> writeTrajectory(const sim::SimulationConfig& simulation,
                                      const std::string& path) {
  std::vector<io::TrajectorySample> samples;
  for (const sim::SensorPose& pose : sim::columnPoses(simulation)) {
    samples.push_back({pose.time_s, toEigen(pose.position), yawQuaternion(pose.yaw_rad)});
  }
  auto trajectory = io::Trajectory::fromSamples(std::move(samples), true, path);
  if (!trajectory) {
    return Unexpected(trajectory.error());
  }
  return io::saveTrajectory(*trajectory, path);
}

/// Combinations of outputs the flags cannot make; prints why and returns false.
bool checkOutputs(const SimulateFlags& f) {
  if (f.rays.empty() && f.points.empty() && f.truth.empty()) {
    printError("simulate",
               "nothing to write: give --rays OUT.ply, --points OUT.ply --trajectory OUT.txt or "
               "--truth OUT.csv");
    return false;
  }
  if (f.points.empty() != f.trajectory.empty()) {
    printError("simulate",
               "--points and --trajectory go together: a point cloud needs the sensor "
               "trajectory to be mapped");
    return false;
  }
  return true;
}

/// The sensors the scene has, narrowed by --sensors; checks --scans and --points against them.
/// Prints why not and returns nullopt.
std::optional<sim::RecordedSensors> chooseSensors(const SimulateFlags& f,
                                                  const sim::SceneFile& loaded) {
  sim::RecordedSensors sensors{loaded.has_lidar, !loaded.depth_cameras.empty()};
  if (!f.sensors.empty()) {
    const auto named = [&f](const char* sensor) {
      return std::find(f.sensors.begin(), f.sensors.end(), sensor) != f.sensors.end();
    };
    for (const auto& [name, has] : {std::pair{"lidar", sensors.lidar}, {"depth", sensors.depth}}) {
      if (named(name) && !has) {
        printError("simulate", std::string("--sensors ") + name + ": " + f.scene + " has no " +
                                   (std::string(name) == "lidar" ? "lidar" : "depth_cameras"));
        return std::nullopt;
      }
    }
    sensors = {named("lidar"), named("depth")};
  }
  if (f.scans && !loaded.has_lidar) {
    printError("simulate", "--scans counts lidar revolutions, and " + f.scene +
                               " has no lidar (its duration sets the camera frames)");
    return std::nullopt;
  }
  if (!f.points.empty() && sensors.depth) {
    printError("simulate",
               "--points holds the lidar's returns with its column trajectory: write depth "
               "cameras with --rays, or give --sensors lidar");
    return std::nullopt;
  }
  return sensors;
}

/// The staged names of the outputs (empty where not asked for).
struct SimulateTemps {
  std::string rays, points, trajectory, truth;
};

/// What a simulation made, for the files and the summary line.
struct Simulated {
  std::vector<Ray> rays;
  std::uint64_t depth_frames = 0;
  std::string truth_csv;
  std::uint64_t truth_cells = 0;
};

/// Writes the outputs to their staged names; prints why not. `written` lists them for the
/// summary.
bool writeOutputs(const SimulateFlags& f, const sim::SimulationConfig& simulation, Simulated& made,
                  const SimulateTemps& temps, std::vector<std::string>& written) {
  if (!f.rays.empty()) {
    if (auto ok = writeRays(made.rays, temps.rays, io::PlyLayout::kRayCloud); !ok) {
      printError("simulate", "--rays: " + ok.error().message);
      return false;
    }
    written.push_back(f.rays);
  }
  if (!f.points.empty()) {
    auto points = writeRays(made.rays, temps.points, io::PlyLayout::kPointCloud);
    if (!points) {
      printError("simulate", "--points: " + points.error().message);
      return false;
    }
    if (auto ok = writeTrajectory(simulation, temps.trajectory); !ok) {
      printError("simulate", "--trajectory: " + ok.error().message);
      return false;
    }
    written.push_back(f.points + " (" + withCommas(*points) + " points)");
    written.push_back(f.trajectory);
  }
  if (!f.truth.empty()) {
    made.truth_csv.pop_back();  // writeTextFile ends the last line
    if (auto ok = writeTextFile(temps.truth, made.truth_csv); !ok) {
      printError("simulate", "--truth: " + ok.error().message);
      return false;
    }
    written.push_back(f.truth + " (" + withCommas(made.truth_cells) + " cells)");
  }
  return true;
}

void printSummary(const sim::SceneFile& loaded, const Simulated& made,
                  const std::vector<std::string>& written) {
  std::string files;
  for (const std::string& w : written) {
    files += (files.empty() ? "" : ", ") + w;
  }
  const auto no_returns = static_cast<std::uint64_t>(
      std::count_if(made.rays.begin(), made.rays.end(),
                    [](const Ray& r) { return (r.flags & kRayNoReturn) != 0; }));
  const int scans = made.rays.empty() ? 0 : loaded.simulation.scans;
  const std::string frames = made.depth_frames > 0
                                 ? ", " + withCommas(made.depth_frames) + " depth frames"
                                 : std::string();
  std::printf("simulated %s: %d scans, %s rays, %s no-return%s -> %s\n", loaded.scene.name.c_str(),
              scans, withCommas(made.rays.size()).c_str(), withCommas(no_returns).c_str(),
              frames.c_str(), files.c_str());
}

int runSimulate(const SimulateFlags& f) {
  const char* command = "simulate";
  if (!checkOutputs(f)) {
    return kExitUsage;
  }
  std::optional<Rect> truth_box;
  if (!f.truth_box.empty()) {
    auto box = parseRect(f.truth_box, "--truth-box");
    if (!box) {
      printError(command, box.error().message);
      return kExitUsage;
    }
    truth_box = *box;
  }
  // Staged before the work (an output that is the scene or cannot be written fails now) and
  // renamed together at the end.
  io::StagedOutputs staged(command);
  staged.input(f.scene, "the scene file");
  SimulateTemps temps;
  for (const auto& [path, name, temp] :
       {std::tuple{&f.rays, "--rays", &temps.rays},
        std::tuple{&f.points, "--points", &temps.points},
        std::tuple{&f.trajectory, "--trajectory", &temps.trajectory},
        std::tuple{&f.truth, "--truth", &temps.truth}}) {
    if (!path->empty()) {
      auto staged_path = staged.add(*path, name);
      if (!staged_path) {
        printError(command, staged_path.error().message);
        return exitCodeFor(staged_path.error());
      }
      *temp = std::move(*staged_path);
    }
  }
  auto loaded = sim::loadSceneFile(f.scene);
  if (!loaded) {
    printError(command, loaded.error().message);
    return kExitFailure;
  }
  const sim::Scene& scene = loaded->scene;
  sim::SimulationConfig& simulation = loaded->simulation;
  const auto sensors = chooseSensors(f, *loaded);
  if (!sensors) {
    return kExitUsage;
  }
  simulation.seed = f.seed.value_or(simulation.seed);
  simulation.scans = sensors->lidar ? f.scans.value_or(simulation.scans) : 0;

  Simulated made;
  if (!f.truth.empty()) {
    if (!truth_box) {
      truth_box = sceneRect(scene, simulation.path);
    }
    const double reference =
        f.truth_reference.value_or(scene.has_ground ? scene.ground_height : 0.0);
    made.truth_cells =
        truthCsv(scene, *truth_box, f.truth_resolution, reference, f.min_clearance, made.truth_csv);
  }
  if (!f.rays.empty() || !f.points.empty()) {
    const double duration_s =
        f.scans ? *f.scans * simulation.lidar.scan_period_s : loaded->duration_s;
    auto recorded = sim::recordScene(*loaded, *sensors, duration_s, made.rays, made.depth_frames);
    if (!recorded) {
      printError(command, recorded.error().message);
      return kExitFailure;
    }
  }
  std::vector<std::string> written;
  if (!writeOutputs(f, simulation, made, temps, written)) {
    return kExitFailure;
  }
  if (auto ok = staged.commit(); !ok) {
    printError(command, ok.error().message);
    return kExitFailure;
  }
  if (!f.quiet) {
    printSummary(*loaded, made, written);
  }
  return kExitOk;
}

}  // namespace

void addSimulateCommand(CLI::App& app, int* exit_code) {
  auto flags = std::make_shared<SimulateFlags>();
  CLI::App* c = app.add_subcommand(
      "simulate",
      "Simulate a scene file's lidar and depth cameras (docs/scenes.md): rays, points, true "
      "heights");
  c->add_option("scene", flags->scene, "Scene file (.yaml)")->required();
  c->add_option("--rays", flags->rays, "Ray-cloud PLY to write (every ray, no-returns included)");
  c->add_option("--points", flags->points,
                "Point-cloud PLY to write (returns only: x y z time intensity scan)");
  c->add_option("--trajectory", flags->trajectory,
                "Sensor trajectory to write with --points (time x y z qw qx qy qz per column)");
  c->add_option("--truth", flags->truth,
                "True height field to write as CSV (x,y,height,clearance)");
  c->add_option("--truth-resolution", flags->truth_resolution, "Cell size of the truth grid (m)")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  c->add_option("--truth-box", flags->truth_box,
                "xmin,ymin,xmax,ymax of the truth grid (default: the objects and the sensor path)");
  c->add_option("--truth-reference", flags->truth_reference,
                "Height the true surface is searched around (default: the ground height)");
  c->add_option("--min-clearance", flags->min_clearance, "Free space a surface needs above it (m)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  c->add_option("--seed", flags->seed, "Random seed (default: the scene file's)");
  c->add_option("--scans", flags->scans, "Scans to simulate (default: the scene file's)")
      ->check(CLI::Range(1, 100000));
  c->add_option("--sensors", flags->sensors,
                "Sensors to run, comma-separated: lidar, depth (default: all the scene has; depth "
                "frames become rays through raymapd's depth-image decoder)")
      ->delimiter(',')
      ->check(CLI::IsMember({"lidar", "depth"}));
  c->add_flag("-q,--quiet", flags->quiet, "Print nothing on success");
  c->callback([flags, exit_code] { *exit_code = runSimulate(*flags); });
}

}  // namespace raymap::cli
