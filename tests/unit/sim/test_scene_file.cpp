// SPDX-License-Identifier: BSD-3-Clause
// Scene files: what each object expands to, the lidar, depth-camera and trajectory sections, one
// test per class
// of error (each message names the file, the key path and the reason), and the shipped scenes.
#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <optional>
#include <ostream>
#include <set>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "src/sim/scene_file.hpp"
#include "tests/support/temp_dir.hpp"

namespace raymap::sim {
namespace {

constexpr double kSceneFileTolerance = 1e-12;

/// A trajectory of 1 s at 1 m/s: 10 scans at the default 10 Hz.
const std::string kTrajectory =
    "trajectory:\n"
    "  waypoints: [[0, 0, 1], [1, 0, 1]]\n"
    "  speed: 1\n";

SceneFile parseOk(const std::string& text) {
  auto file = parseSceneFile(text, "test.yaml");
  EXPECT_TRUE(file.has_value()) << file.error().message;
  return file ? *file : SceneFile{};
}

bool sameBox(const Box& a, const Box& b) {
  for (int i = 0; i < 3; ++i) {
    if (std::abs(a.min[i] - b.min[i]) > kSceneFileTolerance ||
        std::abs(a.max[i] - b.max[i]) > kSceneFileTolerance) {
      return false;
    }
  }
  return true;
}

// ---- what the objects become ----

TEST(SceneFile, BoxAndWallBecomeBoxes) {
  const SceneFile file = parseOk(
      "objects:\n"
      "  - {type: box, min: [0, 0, 0], max: [1, 2, 3]}\n"
      "  - {type: wall, from: [-4, -3], to: [4, -3], height: 2.5, thickness: 0.2}\n"
      "  - {type: wall, from: [2, 5], to: [2, 1], height: 1, thickness: 0.4, base: 0.5}\n" +
      kTrajectory);

  ASSERT_EQ(file.scene.boxes.size(), 3u);
  EXPECT_TRUE(sameBox(file.scene.boxes[0], {{0, 0, 0}, {1, 2, 3}}));
  EXPECT_TRUE(sameBox(file.scene.boxes[1], {{-4.1, -3.1, 0.0}, {4.1, -2.9, 2.5}}));
  EXPECT_TRUE(sameBox(file.scene.boxes[2], {{1.8, 0.8, 0.5}, {2.2, 5.2, 1.5}}));
}

TEST(SceneFile, StairsAreOneSolidBoxPerStep) {
  const SceneFile file = parseOk(
      "objects:\n"
      "  - {type: stairs, start: [2, 0, 0.1], direction: -y, steps: 3, rise: 0.17, run: 0.3,"
      " width: 1.2}\n" +
      kTrajectory);

  ASSERT_EQ(file.scene.boxes.size(), 3u);
  EXPECT_TRUE(sameBox(file.scene.boxes[0], {{1.4, -0.3, 0.1}, {2.6, 0.0, 0.27}}));
  EXPECT_TRUE(sameBox(file.scene.boxes[2], {{1.4, -0.9, 0.1}, {2.6, -0.6, 0.61}}));
}

TEST(SceneFile, TableIsATopOnFourLegs) {
  const SceneFile file = parseOk(
      "objects:\n"
      "  - {type: table, centre: [1, 0.5], size: [1.6, 0.9], height: 0.75, top_thickness: 0.04,"
      " leg_size: 0.06}\n" +
      kTrajectory);

  ASSERT_EQ(file.scene.boxes.size(), 5u);
  EXPECT_TRUE(sameBox(file.scene.boxes[0], {{0.2, 0.05, 0.71}, {1.8, 0.95, 0.75}}));
  EXPECT_TRUE(sameBox(file.scene.boxes[1], {{0.2, 0.05, 0.0}, {0.26, 0.11, 0.71}}));
  EXPECT_TRUE(sameBox(file.scene.boxes[4], {{1.74, 0.89, 0.0}, {1.8, 0.95, 0.71}}));
}

TEST(SceneFile, RampPoleAndDitchStandOnTheGround) {
  const SceneFile file = parseOk(
      "ground: {height: 0.5}\n"
      "objects:\n"
      "  - {type: ramp, min: [0, 0, 0.5], max: [4, 2, 1.5], rises: -y}\n"
      "  - {type: pole, at: [3, 4], radius: 0.1, height: 2}\n"
      "  - {type: ditch, min: [5, -1], max: [6, 1], depth: 0.8}\n" +
      kTrajectory);

  EXPECT_EQ(file.scene.ground_height, 0.5);
  ASSERT_EQ(file.scene.ramps.size(), 1u);
  EXPECT_EQ(file.scene.ramps[0].axis, RampAxis::kMinusY);
  ASSERT_EQ(file.scene.poles.size(), 1u);
  EXPECT_EQ(file.scene.poles[0].z_min, 0.5);
  EXPECT_EQ(file.scene.poles[0].z_max, 2.5);
  ASSERT_EQ(file.scene.ditches.size(), 1u);
  EXPECT_EQ(file.scene.ditches[0].depth, 0.8);
}

TEST(SceneFile, GroundForms) {
  EXPECT_TRUE(parseOk(kTrajectory).scene.has_ground);
  EXPECT_EQ(parseOk(kTrajectory).scene.ground_height, 0.0);
  EXPECT_FALSE(parseOk("ground: none\n" + kTrajectory).scene.has_ground);
  EXPECT_EQ(parseOk("ground: -1.5\n" + kTrajectory).scene.ground_height, -1.5);
}

TEST(SceneFile, LidarSectionAndDefaults) {
  const SceneFile file = parseOk(
      "lidar: {beams: 16, elevation_min_deg: -20, elevation_max_deg: 20, columns: 900,"
      " rate_hz: 20, max_range: 25, min_range: 0.5, range_noise: 0.02, dropout: 0.05}\n" +
      kTrajectory);
  const LidarModel& lidar = file.simulation.lidar;

  EXPECT_EQ(lidar.beams, 16);
  EXPECT_EQ(lidar.elevation_min_deg, -20.0);
  EXPECT_EQ(lidar.columns, 900);
  EXPECT_DOUBLE_EQ(lidar.scan_period_s, 0.05);
  EXPECT_EQ(lidar.max_range_m, 25.0);
  EXPECT_EQ(lidar.min_range_m, 0.5);
  EXPECT_EQ(lidar.range_noise_m, 0.02);
  EXPECT_EQ(lidar.dropout, 0.05);
  EXPECT_EQ(file.simulation.scans, 20);  // 1 s at 20 Hz
  EXPECT_EQ(parseOk(kTrajectory).simulation.lidar.beams, LidarModel{}.beams);
}

TEST(SceneFile, ScansFromTheTrajectoryADurationOrGiven) {
  EXPECT_EQ(parseOk(kTrajectory).simulation.scans, 10);
  EXPECT_EQ(parseOk(kTrajectory + "duration: 2.5\n").simulation.scans, 25);
  EXPECT_EQ(parseOk(kTrajectory + "scans: 3\nseed: 42\n").simulation.scans, 3);
  EXPECT_EQ(parseOk(kTrajectory + "seed: 18446744073709551615\n").simulation.seed,
            18446744073709551615u);
}

/// A camera with only its required keys (1 s of trajectory: 15 frames at the default 15 Hz).
const std::string kCamera =
    "depth_cameras:\n"
    "  - {name: front, width: 64, height: 48, hfov_deg: 87, mount: {position: [0.3, 0, 0]}}\n";

TEST(SceneFile, DepthCamerasSectionAndDefaults) {
  const SceneFile file = parseOk(
      "depth_cameras:\n"
      "  - name: body_front\n"
      "    width: 424\n"
      "    height: 240\n"
      "    hfov_deg: 87\n"
      "    cx: 210.5\n"
      "    cy: 121\n"
      "    distortion: [-0.05, 0.02, 0.001, -0.001, 0]\n"
      "    mount: {position: [0.4, 0.0, 0.05], rpy_deg: [1, 45, -2]}\n"
      "    rate_hz: 5\n"
      "    max_range: 2\n"
      "    min_range: 0.2\n"
      "    noise: 0.003\n"
      "    encoding: 16UC1\n"
      "    downsample: 2\n" +
      kCamera.substr(kCamera.find("  - ")) + kTrajectory);

  ASSERT_EQ(file.depth_cameras.size(), 2u);
  const DepthCameraModel& c = file.depth_cameras[0];
  EXPECT_EQ(c.name, "body_front");
  EXPECT_EQ(c.width, 424u);
  EXPECT_EQ(c.height, 240u);
  EXPECT_EQ(c.hfov_deg, 87.0);
  EXPECT_EQ(c.cx, std::optional<double>(210.5));
  EXPECT_EQ(c.cy, std::optional<double>(121.0));
  EXPECT_EQ(c.distortion, (std::array<double, 5>{-0.05, 0.02, 0.001, -0.001, 0.0}));
  EXPECT_EQ(c.mount.position_m, (Vec3d{0.4, 0.0, 0.05}));
  EXPECT_EQ(c.mount.roll_deg, 1.0);
  EXPECT_EQ(c.mount.pitch_deg, 45.0);
  EXPECT_EQ(c.mount.yaw_deg, -2.0);
  EXPECT_EQ(c.rate_hz, 5.0);
  EXPECT_EQ(c.max_range_m, 2.0);
  EXPECT_EQ(c.min_range_m, 0.2);
  EXPECT_EQ(c.depth_noise_m, 0.003);
  EXPECT_EQ(c.encoding, DepthEncoding::k16UC1);
  EXPECT_EQ(c.downsample, 2u);
  const DepthCameraModel& d = file.depth_cameras[1];
  const DepthCameraModel defaults;
  EXPECT_EQ(d.name, "front");
  EXPECT_FALSE(d.cx.has_value());
  EXPECT_EQ(d.distortion, defaults.distortion);
  EXPECT_EQ(d.mount.pitch_deg, 0.0);
  EXPECT_EQ(d.rate_hz, defaults.rate_hz);
  EXPECT_EQ(d.max_range_m, defaults.max_range_m);
  EXPECT_EQ(d.min_range_m, defaults.min_range_m);
  EXPECT_EQ(d.depth_noise_m, defaults.depth_noise_m);
  EXPECT_EQ(d.encoding, DepthEncoding::k32FC1);
  EXPECT_EQ(d.downsample, 1u);
  // Cameras without `lidar:` run alone, over the trajectory's second.
  EXPECT_FALSE(file.has_lidar);
  EXPECT_EQ(file.simulation.scans, 0);
  EXPECT_DOUBLE_EQ(file.duration_s, 1.0);
}

TEST(SceneFile, LidarIsOptionalBesideCameras) {
  const SceneFile lidar_only = parseOk(kTrajectory);
  const SceneFile both = parseOk("lidar: {rate_hz: 20}\n" + kCamera + kTrajectory + "scans: 4\n");
  const SceneFile cameras_for = parseOk(kCamera + kTrajectory + "duration: 0.5\n");

  EXPECT_TRUE(lidar_only.has_lidar);  // a file without sensors keeps the default lidar
  EXPECT_TRUE(lidar_only.depth_cameras.empty());
  EXPECT_DOUBLE_EQ(lidar_only.duration_s, 1.0);
  EXPECT_TRUE(both.has_lidar);
  EXPECT_EQ(both.simulation.scans, 4);
  EXPECT_DOUBLE_EQ(both.duration_s, 0.2);  // 4 scans at 20 Hz
  EXPECT_FALSE(cameras_for.has_lidar);
  EXPECT_DOUBLE_EQ(cameras_for.duration_s, 0.5);
}

TEST(SceneFile, PosesTakeTheHeadingInDegrees) {
  const SceneFile file = parseOk(
      "trajectory:\n"
      "  poses: [[0, 0, 0, 1, 0], [2, 2, 0, 1, 90]]\n");

  ASSERT_EQ(file.simulation.path.knots().size(), 2u);
  EXPECT_NEAR(file.simulation.path.knots()[1].yaw_rad, std::numbers::pi / 2.0, kSceneFileTolerance);
  EXPECT_EQ(file.simulation.scans, 20);
}

TEST(SceneFile, NameFromTheFileOrTheText) {
  EXPECT_EQ(parseOk(kTrajectory).scene.name, "test");
  EXPECT_EQ(parseOk("name: my yard\n" + kTrajectory).scene.name, "my yard");
}

// ---- errors: each names the file, the key path and the reason ----

struct ErrorCase {
  const char* label;
  std::string text;
  std::string expected;  ///< "KEY.PATH: reason" part of the message
};

void PrintTo(const ErrorCase& c, std::ostream* out) { *out << c.label; }

class SceneFileError : public testing::TestWithParam<ErrorCase> {};

TEST_P(SceneFileError, NamesTheFileTheKeyAndTheReason) {
  const ErrorCase& c = GetParam();

  const auto file = parseSceneFile(c.text, "scenes/bad.yaml");

  ASSERT_FALSE(file.has_value()) << c.label;
  const std::string& message = file.error().message;
  EXPECT_EQ(message.rfind("scenes/bad.yaml: ", 0), 0u) << message;
  EXPECT_NE(message.find(c.expected), std::string::npos)
      << "expected '" << c.expected << "' in: " << message;
}

const std::string kThreeBoxes =
    "objects:\n"
    "  - {type: box, min: [0, 0, 0], max: [1, 1, 1]}\n"
    "  - {type: box, min: [2, 0, 0], max: [3, 1, 1]}\n"
    "  - {type: box, min: [4, 0, 0], max: [5, 1, 1]}\n";

INSTANTIATE_TEST_SUITE_P(
    Classes, SceneFileError,
    testing::Values(
        ErrorCase{"syntax", "objects: [\n", "not valid YAML"},
        ErrorCase{"not a mapping", "- 1\n- 2\n", "expected a mapping"},
        ErrorCase{"unknown top-level key", "colour: red\n" + kTrajectory,
                  "line 1: colour: unknown key (known here: "},
        ErrorCase{"misspelt key before the missing one",
                  "trajetory: {waypoints: [[0, 0, 1], [1, 0, 1]], speed: 1}\n",
                  "trajetory: unknown key"},
        ErrorCase{"unknown object key",
                  "objects:\n  - {type: box, min: [0, 0, 0], max: [1, 1, 1], colour: red}\n" +
                      kTrajectory,
                  "objects[0].colour: unknown key"},
        ErrorCase{"duplicate key", "seed: 1\nseed: 2\n" + kTrajectory, "seed: duplicate key"},
        ErrorCase{"missing key",
                  kThreeBoxes +
                      "  - {type: stairs, start: [0, 0, 0], direction: +x, steps: 3, run: 0.3,"
                      " width: 1}\n" +
                      kTrajectory,
                  "line 5: objects[3].rise: required key missing"},
        ErrorCase{"wrong type",
                  kThreeBoxes +
                      "  - {type: stairs, start: [0, 0, 0], direction: +x, steps: 3, rise: high,"
                      " run: 0.3, width: 1}\n" +
                      kTrajectory,
                  "objects[3].rise: expected a number"},
        ErrorCase{"negative size",
                  kThreeBoxes +
                      "  - {type: stairs, start: [0, 0, 0], direction: +x, steps: 3,"
                      " rise: -0.17, run: 0.3, width: 1}\n" +
                      kTrajectory,
                  "objects[3].rise: must be > 0 (got -0.17)"},
        ErrorCase{"not an integer",
                  "objects:\n  - {type: stairs, start: [0, 0, 0], direction: +x, steps: 2.5,"
                  " rise: 0.2, run: 0.3, width: 1}\n" +
                      kTrajectory,
                  "objects[0].steps: expected an integer"},
        ErrorCase{"wrong list shape",
                  "objects:\n  - {type: box, min: [0, 0], max: [1, 1, 1]}\n" + kTrajectory,
                  "objects[0].min: expected [x, y, z] (a list of 3 numbers)"},
        ErrorCase{"empty box",
                  "objects:\n  - {type: box, min: [0, 0, 0], max: [1, 0, 1]}\n" + kTrajectory,
                  "objects[0].max: must exceed min on every axis"},
        ErrorCase{"unknown object type", "objects:\n  - {type: crate}\n" + kTrajectory,
                  "objects[0].type: must be box, wall, ramp, stairs, table, pole or ditch (got "
                  "'crate')"},
        ErrorCase{
            "bad choice",
            "objects:\n  - {type: ramp, min: [0, 0, 0], max: [1, 1, 1], rises: up}\n" + kTrajectory,
            "objects[0].rises: must be +x, -x, +y or -y (got 'up')"},
        ErrorCase{"slanted wall",
                  "objects:\n  - {type: wall, from: [0, 0], to: [3, 4], height: 2,"
                  " thickness: 0.2}\n" +
                      kTrajectory,
                  "objects[0].to: a wall runs along x or y"},
        ErrorCase{"table legs too wide",
                  "objects:\n  - {type: table, centre: [0, 0], size: [1, 0.5], height: 0.7,"
                  " top_thickness: 0.04, leg_size: 0.3}\n" +
                      kTrajectory,
                  "objects[0].leg_size: two legs must fit"},
        ErrorCase{"overlapping ditches",
                  "objects:\n"
                  "  - {type: ditch, min: [0, 0], max: [2, 2], depth: 1}\n"
                  "  - {type: ditch, min: [1, 1], max: [3, 3], depth: 1}\n" +
                      kTrajectory,
                  "objects[1].min: overlaps the ditch objects[0]"},
        ErrorCase{
            "ditch without ground",
            "ground: none\nobjects:\n  - {type: ditch, min: [0, 0], max: [2, 2], depth: 1}\n" +
                kTrajectory,
            "objects[0].type: a ditch is a hole in the ground"},
        ErrorCase{"bad ground", "ground: flat\n" + kTrajectory,
                  "ground: expected a height, {height: H} or none"},
        ErrorCase{"lidar integer out of range", "lidar: {beams: 0}\n" + kTrajectory,
                  "lidar.beams: must be from 1 to 4096 (got 0)"},
        ErrorCase{"probability out of range", "lidar: {dropout: 1.5}\n" + kTrajectory,
                  "lidar.dropout: must be a probability from 0 to 1 (got 1.5)"},
        ErrorCase{"ranges in the wrong order",
                  "lidar: {min_range: 50, max_range: 40}\n" + kTrajectory,
                  "lidar.min_range: must be less than max_range"},
        ErrorCase{"missing trajectory", "seed: 1\n", "trajectory: required key missing"},
        ErrorCase{"waypoints and poses",
                  "trajectory: {waypoints: [[0, 0, 1]], speed: 1, poses: [[0, 0, 0, 1, 0]]}\n",
                  "trajectory: give either waypoints (with speed) or poses"},
        ErrorCase{"waypoints without speed", "trajectory: {waypoints: [[0, 0, 1], [1, 0, 1]]}\n",
                  "trajectory.speed: required key missing"},
        ErrorCase{"speed with poses",
                  "trajectory: {poses: [[0, 0, 0, 1, 0], [1, 1, 0, 1, 0]], speed: 2}\n",
                  "trajectory.speed: applies to waypoints only"},
        ErrorCase{"poses out of order",
                  "trajectory: {poses: [[0, 0, 0, 1, 0], [2, 1, 0, 1, 0], [1, 2, 0, 1, 0]]}\n",
                  "trajectory.poses: pose 2: its time does not come after"},
        ErrorCase{"wrong pose shape", "trajectory: {poses: [[0, 0, 0, 1]]}\n",
                  "trajectory.poses[0]: expected [t, x, y, z, yaw_deg] (a list of 5 numbers)"},
        ErrorCase{"shorter than a scan", "trajectory: {waypoints: [[0, 0, 1]], speed: 1}\n",
                  "trajectory: lasts 0 s, less than one scan"},
        ErrorCase{"scans and duration", kTrajectory + "scans: 3\nduration: 2\n",
                  "duration: give scans or duration, not both"},
        ErrorCase{"cameras not a list", "depth_cameras: {name: a}\n" + kTrajectory,
                  "line 1: depth_cameras: expected a non-empty list of cameras"},
        ErrorCase{"camera without a name",
                  "depth_cameras:\n  - {width: 64, height: 48, hfov_deg: 87,"
                  " mount: {position: [0, 0, 0]}}\n" +
                      kTrajectory,
                  "line 2: depth_cameras[0].name: required key missing"},
        ErrorCase{"unknown camera key",
                  "depth_cameras:\n  - {name: a, width: 64, height: 48, hfov_deg: 87,"
                  " mount: {position: [0, 0, 0]}, fps: 30}\n" +
                      kTrajectory,
                  "depth_cameras[0].fps: unknown key (known here: "},
        ErrorCase{"field of view out of range",
                  "depth_cameras:\n  - {name: a, width: 64, height: 48, hfov_deg: 180,"
                  " mount: {position: [0, 0, 0]}}\n" +
                      kTrajectory,
                  "depth_cameras[0].hfov_deg: must be between 0 and 180 degrees (got 180)"},
        ErrorCase{"camera width zero",
                  "depth_cameras:\n  - {name: a, width: 0, height: 48, hfov_deg: 87,"
                  " mount: {position: [0, 0, 0]}}\n" +
                      kTrajectory,
                  "depth_cameras[0].width: must be from 1 to 65535 (got 0)"},
        ErrorCase{"distortion shape",
                  "depth_cameras:\n  - {name: a, width: 64, height: 48, hfov_deg: 87,"
                  " distortion: [0.1, 0.0], mount: {position: [0, 0, 0]}}\n" +
                      kTrajectory,
                  "depth_cameras[0].distortion: expected [k1, k2, p1, p2, k3]"},
        ErrorCase{"folding distortion",
                  "depth_cameras:\n  - {name: a, width: 64, height: 48, hfov_deg: 87,"
                  " distortion: [-0.5, 0, 0, 0, 0], mount: {position: [0, 0, 0]}}\n" +
                      kTrajectory,
                  "depth_cameras[0].distortion: camera distortion D cannot be inverted"},
        ErrorCase{"mount without position",
                  "depth_cameras:\n  - {name: a, width: 64, height: 48, hfov_deg: 87,"
                  " mount: {rpy_deg: [0, 45, 0]}}\n" +
                      kTrajectory,
                  "depth_cameras[0].mount.position: required key missing"},
        ErrorCase{"mount angles shape",
                  "depth_cameras:\n  - {name: a, width: 64, height: 48, hfov_deg: 87,"
                  " mount: {position: [0, 0, 0], rpy_deg: [45]}}\n" +
                      kTrajectory,
                  "depth_cameras[0].mount.rpy_deg: expected [roll, pitch, yaw]"},
        ErrorCase{"camera ranges in the wrong order",
                  "depth_cameras:\n  - {name: a, width: 64, height: 48, hfov_deg: 87,"
                  " mount: {position: [0, 0, 0]}, min_range: 3, max_range: 2}\n" +
                      kTrajectory,
                  "depth_cameras[0].min_range: must be less than max_range"},
        ErrorCase{"negative noise",
                  "depth_cameras:\n  - {name: a, width: 64, height: 48, hfov_deg: 87,"
                  " mount: {position: [0, 0, 0]}, noise: -0.01}\n" +
                      kTrajectory,
                  "depth_cameras[0].noise: must be >= 0 (got -0.01)"},
        ErrorCase{"unknown encoding",
                  "depth_cameras:\n  - {name: a, width: 64, height: 48, hfov_deg: 87,"
                  " mount: {position: [0, 0, 0]}, encoding: rgb8}\n" +
                      kTrajectory,
                  "depth_cameras[0].encoding: must be 16UC1 or 32FC1 (got 'rgb8')"},
        ErrorCase{"duplicate camera names",
                  kCamera + kCamera.substr(kCamera.find("  - ")) + kTrajectory,
                  "line 3: depth_cameras[1].name: another camera is called 'front'"},
        ErrorCase{"scans without a lidar", kCamera + kTrajectory + "scans: 3\n",
                  "scans: counts lidar revolutions, and the scene has no lidar"},
        ErrorCase{"shorter than a frame",
                  kCamera + "trajectory: {waypoints: [[0, 0, 1]], speed: 1}\n",
                  "trajectory: lasts 0 s, less than one frame of camera 'front'"}));

TEST(SceneFile, MissingFileNamesThePath) {
  test::TempDir dir;

  const auto file = loadSceneFile(dir.file("absent.yaml"));

  ASSERT_FALSE(file.has_value());
  EXPECT_NE(file.error().message.find("absent.yaml"), std::string::npos) << file.error().message;
  EXPECT_EQ(file.error().code, ErrorCode::kIo);
}

TEST(SceneFile, ErrorsInAFileNameItsPath) {
  test::TempDir dir;
  const std::string path = dir.file("scene.yaml");
  std::ofstream(path) << "objects:\n  - {type: pole, at: [0, 0], radius: -1, height: 2}\n"
                      << kTrajectory;

  const auto file = loadSceneFile(path);

  ASSERT_FALSE(file.has_value());
  EXPECT_EQ(file.error().message, path + ": line 2: objects[0].radius: must be > 0 (got -1)");
}

// ---- the shipped scenes ----

TEST(ShippedScenes, EveryOneLoadsAndSimulatesWithinTheSizeBudget) {
  std::set<std::string> names;
  for (const auto& entry : std::filesystem::directory_iterator(RAYMAP_SCENES_DIR)) {
    if (entry.path().extension() != ".yaml") {
      continue;
    }
    const auto file = loadSceneFile(entry.path().string());
    ASSERT_TRUE(file.has_value()) << file.error().message;
    EXPECT_EQ(file->scene.name, entry.path().stem().string());
    names.insert(file->scene.name);
    // Cameras: at most about 3 million rays in all (what the CLI tests map in seconds).
    std::size_t camera_rays = 0;
    for (const DepthCameraModel& model : file->depth_cameras) {
      const auto camera = DepthCamera::create(model);
      ASSERT_TRUE(camera.has_value()) << camera.error().message;
      const std::size_t n = model.downsample;
      camera_rays += ((model.width + n - 1) / n) * ((model.height + n - 1) / n) *
                     static_cast<std::size_t>(frameCount(file->duration_s, model.rate_hz));
    }
    EXPECT_LE(camera_rays, 3'000'000u) << entry.path();
    if (!file->has_lidar) {
      EXPECT_GT(camera_rays, 0u) << entry.path();
      continue;
    }
    EXPECT_GE(file->simulation.scans, 10) << entry.path();
    EXPECT_LE(file->simulation.scans, 30) << entry.path();
    const LidarModel& lidar = file->simulation.lidar;
    EXPECT_LE(lidar.beams * lidar.columns * file->simulation.scans, 32 * 1024 * 30) << entry.path();
    const std::vector<Ray> rays = simulateScans(file->scene, file->simulation);
    EXPECT_GT(rays.size(), 0u) << entry.path();
  }
  for (const char* name : {"yard", "stairs", "ditch", "room"}) {
    EXPECT_EQ(names.count(name), 1u) << name;
  }
}

}  // namespace
}  // namespace raymap::sim
