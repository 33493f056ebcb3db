// SPDX-License-Identifier: BSD-3-Clause
// `raymap simulate` with depth cameras, end to end (issue 26, "What must hold"): the stairs seen
// by a body camera alone, mapped by `populate` and read by `heightmap`, against the scene's exact
// height field on the CPU and OpenCL, with and without lens distortion; the lidar's near blind
// zone filled by a camera; the summary, determinism and the --sensors errors.
// Frames become rays through raymapd's own depth-image decoder (tools/raymap/simulate_depth.cpp).
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <optional>
#include <ostream>
#include <set>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "src/sim/depth_camera.hpp"
#include "src/sim/scene_file.hpp"
#include "tests/support/cli_runner.hpp"
#include "tests/support/scene_truth.hpp"
#include "tests/support/temp_dir.hpp"

namespace raymap::test {
namespace {

constexpr double kPopulateResolution = 0.1;  // populate's default voxel size
/// The camera's reach along a ray (2 m of depth), what populate integrates.
const std::string kMaxRange = "2";
/// A moderate barrel lens with a little tangential distortion (invertible over a 87° image).
const std::string kLens = "[-0.2, 0.05, 0.001, 0.002, 0]";

using CellKey = std::pair<long, long>;  // floor(x / resolution), floor(y / resolution)

CellKey cellOf(double x, double y) {
  return {static_cast<long>(std::floor(x / kPopulateResolution)),
          static_cast<long>(std::floor(y / kPopulateResolution))};
}

double share(std::size_t part, std::size_t whole) {
  return static_cast<double>(part) / static_cast<double>(whole);
}

/// The elevations of a height-map CSV (x,y,elevation,clearance,kind), NaN where none.
std::map<CellKey, double> readElevations(const std::string& path) {
  std::map<CellKey, double> cells;
  std::istringstream in(readFile(path));
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line.rfind("x,y,elevation,clearance,kind", 0), 0u) << line;
  while (std::getline(in, line)) {
    std::istringstream fields(line);
    std::string x;
    std::string y;
    std::string elevation;
    std::getline(fields, x, ',');
    std::getline(fields, y, ',');
    std::getline(fields, elevation, ',');
    cells[cellOf(std::stod(x), std::stod(y))] = std::strtod(elevation.c_str(), nullptr);
  }
  return cells;
}

/// The true heights of a `simulate --truth` CSV (x,y,height,clearance); absent = no surface.
std::map<CellKey, double> readDepthTruth(const std::string& path) {
  std::map<CellKey, double> cells;
  std::istringstream in(readFile(path));
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line, "x,y,height,clearance");
  while (std::getline(in, line)) {
    std::istringstream fields(line);
    std::string x;
    std::string y;
    std::string height;
    std::getline(fields, x, ',');
    std::getline(fields, y, ',');
    std::getline(fields, height, ',');
    if (!height.empty()) {
      cells[cellOf(std::stod(x), std::stod(y))] = std::stod(height);
    }
  }
  return cells;
}

/// The cells where some valid pixel of some frame of the scene's cameras lands: the footprint,
/// rendered again here with the library.
std::set<CellKey> cameraFootprint(const sim::SceneFile& file) {
  std::set<CellKey> cells;
  for (const sim::DepthCameraModel& model : file.depth_cameras) {
    auto camera = sim::DepthCamera::create(model);
    EXPECT_TRUE(camera.has_value()) << camera.error().message;
    if (!camera) {
      return cells;
    }
    std::vector<float> depth(camera->pixels());
    const double start = file.simulation.path.startTime();
    for (int f = 0; f < sim::frameCount(file.duration_s, model.rate_hz); ++f) {
      const sim::CameraPose pose =
          sim::cameraPose(model.mount, file.simulation.path.at(start + f / model.rate_hz));
      camera->render(file.scene, pose, 0, depth);
      for (std::uint32_t v = 0; v < model.height; ++v) {
        for (std::uint32_t u = 0; u < model.width; ++u) {
          const double z =
              static_cast<double>(depth[static_cast<std::size_t>(v) * model.width + u]);
          if (std::isfinite(z)) {
            const float* r = camera->rays().ray(u, v);
            const Vec3d p =
                pose.toWorld({z * static_cast<double>(r[0]), z * static_cast<double>(r[1]), z});
            cells.insert(cellOf(p.x, p.y));
          }
        }
      }
    }
  }
  return cells;
}

/// "name.yaml" copied into `dir` with the camera's distortion set to kLens.
std::string withLens(const TempDir& dir, const std::string& scene) {
  std::string text = readFile(std::string(RAYMAP_SCENES_DIR) + "/" + scene);
  const std::string anchor = "    hfov_deg: 87\n";
  const std::size_t at = text.find(anchor);
  EXPECT_NE(at, std::string::npos);
  text.insert(at + anchor.size(), "    distortion: " + kLens + "\n");
  const std::string path = dir.file(scene);
  std::ofstream(path) << text;
  return path;
}

/// simulate --rays -> populate -> heightmap --csv; returns the CSV path ("" and a failure when a
/// step fails).
std::string heightMapOf(const TempDir& dir, const std::string& scene,
                        const std::vector<std::string>& simulate_options,
                        const std::string& backend, const std::string& centre, double size) {
  const std::string rays = dir.file("rays.ply");
  const std::string map = dir.file("map.rmap");
  const std::string csv = dir.file("height.csv");
  std::vector<std::string> simulate = {"simulate", scene, "--rays", rays, "-q"};
  simulate.insert(simulate.end(), simulate_options.begin(), simulate_options.end());
  const RunResult s = runRaymap(simulate);
  EXPECT_EQ(s.exit_code, 0) << describe(s);
  const RunResult p = runRaymap(
      {"populate", rays, "--max-range", kMaxRange, "--backend", backend, "--output", map, "-q"});
  EXPECT_EQ(p.exit_code, 0) << describe(p);
  const RunResult h = runRaymap({"heightmap", map, "--center", centre, "--size",
                                 std::to_string(size), "--backend", backend, "--csv", csv, "-q"});
  EXPECT_EQ(h.exit_code, 0) << describe(h);
  return s.exit_code == 0 && p.exit_code == 0 && h.exit_code == 0 ? csv : std::string();
}

// ---------------------------------------------------------------------------------------------
// The stairs seen by the body camera alone

struct StairsCase {
  std::string backend;
  bool distorted = false;
};

void PrintTo(const StairsCase& c, std::ostream* out) {
  *out << c.backend << (c.distorted ? " plumb_bob" : " no distortion");
}

class DepthStairs : public testing::TestWithParam<StairsCase> {};

TEST_P(DepthStairs, HeightMapMatchesTheTrueStepsInTheCameraFootprint) {
  const StairsCase& c = GetParam();
  if (const std::string why = deviceUnavailable(c.backend); !why.empty()) {
    GTEST_SKIP() << why;
  }
  TempDir dir;
  const std::string scene = c.distorted ? withLens(dir, "stairs_depth.yaml")
                                        : std::string(RAYMAP_SCENES_DIR) + "/stairs_depth.yaml";
  const auto file = sim::loadSceneFile(scene);
  ASSERT_TRUE(file.has_value()) << file.error().message;
  ASSERT_FALSE(file->has_lidar);
  const std::string truth_csv = dir.file("truth.csv");

  const std::string csv = heightMapOf(
      dir, scene, {"--truth", truth_csv, "--truth-box", "-1,-2,6,2"}, c.backend, "2.5,0,0.5", 7.0);

  ASSERT_FALSE(csv.empty());
  const std::map<CellKey, double> heights = readElevations(csv);
  const std::map<CellKey, double> truth = readDepthTruth(truth_csv);
  const std::set<CellKey> footprint = cameraFootprint(*file);
  ASSERT_GT(footprint.size(), 300u);
  std::size_t with_elevation = 0;
  std::size_t judged = 0;  // with an elevation and an unambiguous true surface
  std::size_t within_voxel = 0;
  std::size_t within_3cm = 0;
  for (const CellKey& cell : footprint) {
    const auto h = heights.find(cell);
    if (h == heights.end() || std::isnan(h->second)) {
      continue;
    }
    ++with_elevation;
    const Vec3d centre{(static_cast<double>(cell.first) + 0.5) * kPopulateResolution,
                       (static_cast<double>(cell.second) + 0.5) * kPopulateResolution, 0.0};
    // Cells at a step's edge are left out, as in the lidar's height-map tests: noise along the
    // view puts a riser's points into the column before it.
    if (!unambiguousTruth(file->scene, centre, kPopulateResolution, 0.0, 0.5)) {
      continue;
    }
    const auto t = truth.find(cell);
    ASSERT_NE(t, truth.end()) << "no true surface at " << centre.x << ", " << centre.y;
    ++judged;
    const double error = std::fabs(h->second - t->second);
    within_voxel += error <= kPopulateResolution ? 1U : 0U;
    within_3cm += error <= 0.03 ? 1U : 0U;
  }
  const double observed = share(with_elevation, footprint.size());
  const double voxel_share = share(within_voxel, judged);
  const double cm_share = share(within_3cm, judged);
  std::printf(
      "stairs_depth (%s, %s): %zu footprint cells, %.1f %% with an elevation; of %zu judged, "
      "%.1f %% within 0.1 m, %.1f %% within 3 cm\n",
      c.backend.c_str(), c.distorted ? "plumb_bob" : "no distortion", footprint.size(),
      100.0 * observed, judged, 100.0 * voxel_share, 100.0 * cm_share);
  EXPECT_GE(observed, 0.5);
  ASSERT_GT(judged, 200u);
  EXPECT_GE(voxel_share, 0.95);
  EXPECT_GE(cm_share, 0.90);
}

INSTANTIATE_TEST_SUITE_P(Backends, DepthStairs,
                         testing::Values(StairsCase{"cpu", false}, StairsCase{"cpu", true},
                                         StairsCase{"opencl", false}, StairsCase{"opencl", true}));

// ---------------------------------------------------------------------------------------------
// The lidar's blind zone

/// The share of the cells within 2 m of the standing robot (0, 0) that have an elevation.
double observedNearTheRobot(const std::string& csv) {
  std::size_t near = 0;
  std::size_t observed = 0;
  for (const auto& [cell, elevation] : readElevations(csv)) {
    const double x = (static_cast<double>(cell.first) + 0.5) * kPopulateResolution;
    const double y = (static_cast<double>(cell.second) + 0.5) * kPopulateResolution;
    if (std::hypot(x, y) <= 2.0) {
      ++near;
      observed += std::isnan(elevation) ? 0U : 1U;
    }
  }
  EXPECT_GT(near, 1000u);
  return near == 0 ? 0.0 : share(observed, near);
}

TEST(CliSimulateDepth, CameraFillsTheLidarsNearBlindZone) {
  const std::string scene = std::string(RAYMAP_SCENES_DIR) + "/blind_zone.yaml";
  TempDir lidar_dir;
  TempDir both_dir;

  const std::string lidar_only =
      heightMapOf(lidar_dir, scene, {"--sensors", "lidar"}, "cpu", "0,0,0", 6.0);
  const std::string both = heightMapOf(both_dir, scene, {}, "cpu", "0,0,0", 6.0);

  ASSERT_FALSE(lidar_only.empty());
  ASSERT_FALSE(both.empty());
  const double without_camera = observedNearTheRobot(lidar_only);
  const double with_camera = observedNearTheRobot(both);
  std::printf(
      "blind_zone: cells within 2 m of the robot with an elevation: lidar %.1f %%, "
      "lidar + 4 depth cameras %.1f %%\n",
      100.0 * without_camera, 100.0 * with_camera);
  EXPECT_GE(with_camera, without_camera + 0.4);
}

// ---------------------------------------------------------------------------------------------
// The command

TEST(CliSimulateDepth, SummaryCountsFramesAndRaysAndIsDeterministic) {
  TempDir dir;
  const std::string a = dir.file("a.ply");
  const std::string b = dir.file("b.ply");
  const std::string scene = std::string(RAYMAP_SCENES_DIR) + "/stairs_depth.yaml";

  const RunResult first = runRaymap({"simulate", scene, "--rays", a});
  const RunResult second = runRaymap({"simulate", scene, "--rays", b, "-q"});

  ASSERT_EQ(first.exit_code, 0) << describe(first);
  ASSERT_EQ(second.exit_code, 0) << describe(second);
  // 50 frames of 424 x 240 pixels in 4 x 4 blocks: 106 x 60 rays each.
  EXPECT_TRUE(contains(first.out, "simulated stairs_depth: 0 scans, 318,000 rays, ")) << first.out;
  EXPECT_TRUE(contains(first.out, " no-return, 50 depth frames -> " + a)) << first.out;
  EXPECT_TRUE(readFile(a) == readFile(b));
}

TEST(CliSimulateDepth, LidarAndCamerasShareTheRecordingAndSensorsChooses) {
  TempDir dir;
  const std::string scene = std::string(RAYMAP_SCENES_DIR) + "/blind_zone.yaml";

  const RunResult both = runRaymap({"simulate", scene, "--rays", dir.file("both.ply")});
  const RunResult lidar =
      runRaymap({"simulate", scene, "--rays", dir.file("lidar.ply"), "--sensors", "lidar"});
  const RunResult depth =
      runRaymap({"simulate", scene, "--rays", dir.file("depth.ply"), "--sensors", "depth"});
  const RunResult shorter =
      runRaymap({"simulate", scene, "--rays", dir.file("short.ply"), "--scans", "5"});

  ASSERT_EQ(both.exit_code, 0) << describe(both);
  ASSERT_EQ(lidar.exit_code, 0) << describe(lidar);
  ASSERT_EQ(depth.exit_code, 0) << describe(depth);
  ASSERT_EQ(shorter.exit_code, 0) << describe(shorter);
  // 2 s: 20 lidar scans at 10 Hz and 10 frames at 5 Hz from each of 4 cameras; --scans 5 makes it
  // 0.5 s, and floor(0.5 s x 5 Hz) frames, as scans are counted.
  EXPECT_TRUE(contains(both.out, ": 20 scans, ")) << both.out;
  EXPECT_TRUE(contains(both.out, ", 40 depth frames -> ")) << both.out;
  EXPECT_TRUE(contains(lidar.out, ": 20 scans, ")) << lidar.out;
  EXPECT_FALSE(contains(lidar.out, "depth frames")) << lidar.out;
  EXPECT_TRUE(contains(depth.out, ": 0 scans, 254,400 rays, ")) << depth.out;
  EXPECT_TRUE(contains(shorter.out, ": 5 scans, ")) << shorter.out;
  EXPECT_TRUE(contains(shorter.out, ", 8 depth frames -> ")) << shorter.out;
  // The sweeps in time order, each its own scan: 20 + 40 in the ray cloud.
  const RunResult pop =
      runRaymap({"populate", dir.file("both.ply"), "--max-range", "20", "--stats-json", "-", "-q"});
  ASSERT_EQ(pop.exit_code, 0) << describe(pop);
  EXPECT_EQ(jsonValue(pop.out, "scans"), "60") << pop.out;
}

TEST(CliSimulateDepth, SensorOptionErrors) {
  TempDir dir;
  const std::string stairs = std::string(RAYMAP_SCENES_DIR) + "/stairs_depth.yaml";
  const std::string lidar_scene = std::string(RAYMAP_SCENES_DIR) + "/stairs.yaml";

  const RunResult no_lidar =
      runRaymap({"simulate", stairs, "--rays", dir.file("a.ply"), "--sensors", "lidar"});
  const RunResult no_camera =
      runRaymap({"simulate", lidar_scene, "--rays", dir.file("b.ply"), "--sensors", "depth"});
  const RunResult unknown =
      runRaymap({"simulate", stairs, "--rays", dir.file("c.ply"), "--sensors", "sonar"});
  const RunResult scans =
      runRaymap({"simulate", stairs, "--rays", dir.file("d.ply"), "--scans", "3"});
  const RunResult points = runRaymap(
      {"simulate", stairs, "--points", dir.file("p.ply"), "--trajectory", dir.file("t.txt")});

  EXPECT_EQ(no_lidar.exit_code, 2) << describe(no_lidar);
  EXPECT_TRUE(contains(no_lidar.err, "--sensors lidar: " + stairs + " has no lidar"))
      << no_lidar.err;
  EXPECT_EQ(no_camera.exit_code, 2) << describe(no_camera);
  EXPECT_TRUE(contains(no_camera.err, "has no depth_cameras")) << no_camera.err;
  EXPECT_EQ(unknown.exit_code, 2) << describe(unknown);
  EXPECT_TRUE(contains(unknown.err, "sonar")) << unknown.err;
  EXPECT_EQ(scans.exit_code, 2) << describe(scans);
  EXPECT_TRUE(contains(scans.err, "--scans counts lidar revolutions")) << scans.err;
  EXPECT_EQ(points.exit_code, 2) << describe(points);
  EXPECT_TRUE(contains(points.err, "--points holds the lidar's returns")) << points.err;
}

}  // namespace
}  // namespace raymap::test
