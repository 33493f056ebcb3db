// SPDX-License-Identifier: BSD-3-Clause
// Golden outputs: the map files, exports and height maps of fixed inputs are byte for byte (PNG
// images: pixel for pixel) those recorded in tests/golden/outputs.sha256. The manifest was made
// before the front ends were thinned (issue 55), so a refactor that changes a single byte of what
// users get fails here, naming the output and the command that made it.
//
// Inputs: scenes simulated here (a lidar in the room, a depth camera on the stairs), bags written
// by Foxglove's libraries (tests/rosbag/node), and the shared real data sets when present (those
// cases skip without them). Every command runs on the CPU backend, whose maps do not depend on
// the thread count.
//
// A PNG is compared by its decoded image (size, bit depth, colour type, interlace and the rows of
// pixels, read back with libpng), not by its bytes: libpng's compressor, its filter choice and
// their settings may change the bytes of the same image from one libpng to the next, while what a
// user sees is the pixels.
//
// A deliberate change of an output: run the tests with RAYMAP_GOLDEN_UPDATE=FILE, which appends
// every output's "sha256  name" line to FILE instead of comparing, then `sort -k2 FILE` into the
// manifest, and say in the commit why the bytes changed.
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "tests/rosbag/bag_fixture.hpp"
#include "tests/rosbag/depth_bag.hpp"
#include "tests/support/cli_runner.hpp"
#include "tests/support/decoded_png.hpp"
#include "tests/support/golden_manifest.hpp"
#include "tests/support/shared_data.hpp"
#include "tests/support/temp_dir.hpp"

namespace raymap::test {
namespace {

/// name -> SHA-256 (hex) from the manifest.
std::map<std::string, std::string> manifest() {
  std::map<std::string, std::string> out = readSha256Manifest(RAYMAP_GOLDEN_MANIFEST);
  EXPECT_FALSE(out.empty()) << "cannot read " << RAYMAP_GOLDEN_MANIFEST;
  return out;
}

std::string sha256(const std::string& path) {
  const std::string sha = sha256OfFile(path);
  EXPECT_EQ(sha.size(), 64u) << "sha256sum failed on " << path;
  return sha;
}

bool endsWith(const std::string& text, const std::string& suffix) {
  return text.size() >= suffix.size() &&
         text.compare(text.size() - suffix.size(), suffix.size(), suffix) == 0;
}

/// The SHA-256 that stands for the output at `path`: of its bytes, or for a PNG of its decoded
/// image (written beside it as PATH.pixels, decodedPngBytes()). Empty when a PNG does not decode
/// (a test failure says why).
std::string outputSha256(const std::string& path) {
  if (!endsWith(path, ".png")) {
    return sha256(path);
  }
  const std::optional<DecodedPng> png = decodePng(path);
  if (!png) {
    return "";
  }
  const std::string pixels = path + ".pixels";
  std::ofstream(pixels, std::ios::binary) << decodedPngBytes(*png);
  return sha256(pixels);
}

/// Runs raymap commands in one folder and checks the files they write against the manifest.
/// The commands run in that folder and name their files relative to it, because a map file
/// records its input's path as given (gtest_discover_tests runs each test in its own process, so
/// changing the directory is safe).
class Golden {
 public:
  explicit Golden(std::string prefix) : prefix_(std::move(prefix)) {
    std::filesystem::current_path(dir_.path());
  }
  Golden(const Golden&) = delete;
  Golden& operator=(const Golden&) = delete;
  ~Golden() { std::filesystem::current_path(std::filesystem::temp_directory_path()); }

  const TempDir& dir() const { return dir_; }
  /// Links `target` (a shared data file) into the folder as `name`, which is returned.
  std::string link(const std::filesystem::path& target, const std::string& name) const {
    std::filesystem::create_symlink(std::filesystem::absolute(target), dir_.path() / name);
    return name;
  }

  /// Runs `args` (a raymap command) and then checks each of `outputs` (file names in dir()).
  void run(const std::vector<std::string>& args, const std::vector<std::string>& outputs) {
    const RunResult r = runRaymap(args);
    std::string command = "raymap";
    for (const std::string& a : args) {
      command += " " + a;
    }
    ASSERT_EQ(r.exit_code, 0) << command << "\n" << describe(r);
    for (const std::string& output : outputs) {
      check(output, command);
    }
  }

 private:
  void check(const std::string& output, const std::string& command) {
    const std::string name = prefix_ + "/" + output;
    const std::string actual = outputSha256(dir_.file(output));
    ASSERT_FALSE(actual.empty()) << name << ": no image to compare";
    if (const char* update = std::getenv("RAYMAP_GOLDEN_UPDATE"); update != nullptr) {
      static std::mutex lock;
      const std::lock_guard<std::mutex> hold(lock);
      std::ofstream(update, std::ios::app) << actual << "  " << name << "\n";
      return;
    }
    static const std::map<std::string, std::string> expected = manifest();
    const auto it = expected.find(name);
    ASSERT_NE(it, expected.end()) << name << " is not in " << RAYMAP_GOLDEN_MANIFEST;
    EXPECT_EQ(actual, it->second) << name << " changed; made by:\n" << command;
  }

  std::string prefix_;
  TempDir dir_;
};

// A lidar in the room scene: five scans as a ray cloud, and the same returns as a point cloud
// with the sensor's trajectory (and intensities, for NDT-TM).
void simulateRoom() {
  const RunResult r =
      runRaymap({"simulate", std::string(RAYMAP_SCENES_DIR) + "/room.yaml", "--sensors", "lidar",
                 "--scans", "5", "--rays", "room.ply", "--points", "room_points.ply",
                 "--trajectory", "room_trajectory.txt", "-q"});
  ASSERT_EQ(r.exit_code, 0) << describe(r);
}

TEST(GoldenOutputs, OccupancyMapsTheirExportsAndHeightMaps) {
  Golden g("room");
  ASSERT_NO_FATAL_FAILURE(simulateRoom());
  const std::string in = "room.ply";
  g.run({"populate", in, "--max-range", "20", "-o", "ray.rmap", "--ply", "ray_occupied.ply", "-q"},
        {"ray.rmap", "ray_occupied.ply"});
  g.run({"populate", in, "--max-range", "20", "--semantics", "scan", "--hit", "0.7", "--miss",
         "0.4", "-o", "scan.rmap", "-q"},
        {"scan.rmap"});
  g.run({"populate", in, "--max-range", "20", "--min-range", "0.5", "--no-mean", "--segment-length",
         "1", "--resolution", "0.05", "--region-voxels", "16", "-o", "fine.rmap", "-q"},
        {"fine.rmap"});
  for (const char* mode : {"occupied", "free", "mean"}) {
    const std::string out = std::string("ray_") + mode + "_export.ply";
    g.run({"export", "ray.rmap", "--ply", out, "--mode", mode}, {out});
  }
  g.run({"heightmap", "ray.rmap", "--center", "0,0,0.5", "--size", "6", "--csv", "planar.csv",
         "--png", "planar.png", "-q"},
        {"planar.csv", "planar.png"});
  g.run({"heightmap", "ray.rmap", "--center", "1,0.5,0.3", "--size", "4", "--mode", "fill",
         "--min-clearance", "0.3", "--virtual-surfaces", "--csv", "fill.csv", "-q"},
        {"fill.csv"});
}

TEST(GoldenOutputs, AMapLargerThanItsMemoryBudgetIsTheSameMap) {
  Golden g("room");
  ASSERT_NO_FATAL_FAILURE(simulateRoom());
  // 377 regions of 8^3 voxels through a pool of 33, the compressed tier held to 64 KiB so that
  // regions also go to the spill file.
  const std::vector<std::string> base{"populate",        "room.ply", "--max-range", "20",
                                      "--region-voxels", "8",        "-q"};
  g.run(
      concat(base, {"-o", "tiered.rmap", "--max-memory", "200KiB", "--compressed-memory", "64KiB"}),
      {"tiered.rmap"});
  g.run(concat(base, {"-o", "untiered.rmap"}), {"untiered.rmap"});
}

TEST(GoldenOutputs, NdtDecayAndTsdfMapsAndTheirExports) {
  Golden g("room");
  ASSERT_NO_FATAL_FAILURE(simulateRoom());
  const std::string in = "room.ply";
  g.run({"populate", in, "--max-range", "20", "--mode", "ndt-om", "--ndt-sensor-noise", "0.03",
         "-o", "ndt_om.rmap", "-q"},
        {"ndt_om.rmap"});
  for (const char* mode : {"ndt", "ndt-points"}) {
    const std::string out = std::string("ndt_om_") + mode + ".ply";
    g.run({"export", "ndt_om.rmap", "--ply", out, "--mode", mode}, {out});
  }
  g.run({"heightmap", "ndt_om.rmap", "--center", "0,0,0.5", "--size", "6", "--csv",
         "ndt_om_heights.csv", "-q"},
        {"ndt_om_heights.csv"});
  g.run({"populate", "room_points.ply", "--trajectory", "room_trajectory.txt", "--max-range", "20",
         "--mode", "ndt-tm", "--decay-rate", "-o", "ndt_tm.rmap", "-q"},
        {"ndt_tm.rmap"});
  g.run({"populate", in, "--max-range", "20", "--decay-rate", "-o", "decay.rmap", "-q"},
        {"decay.rmap"});
  g.run({"export", "decay.rmap", "--ply", "decay.ply", "--mode", "decay"}, {"decay.ply"});
  g.run({"populate", in, "--max-range", "20", "--mode", "decay", "-o", "decay_only.rmap", "-q"},
        {"decay_only.rmap"});
  g.run({"populate", in, "--max-range", "20", "--mode", "tsdf", "--tsdf-truncation", "0.25", "-o",
         "tsdf.rmap", "-q"},
        {"tsdf.rmap"});
  for (const char* mode : {"tsdf", "tsdf-mesh"}) {
    const std::string out = std::string("tsdf_") + mode + ".ply";
    g.run({"export", "tsdf.rmap", "--ply", out, "--mode", mode}, {out});
  }
}

TEST(GoldenOutputs, PointCloudsWithATrajectory) {
  Golden g("room");
  ASSERT_NO_FATAL_FAILURE(simulateRoom());
  g.run({"populate", "room_points.ply", "--trajectory", "room_trajectory.txt", "--sensor-offset",
         "0.1,0,0.2", "--scan-period", "0", "--max-range", "20", "-o", "points.rmap", "-q"},
        {"points.rmap"});
}

TEST(GoldenOutputs, DepthCameraRays) {
  Golden g("stairs_depth");
  const RunResult r = runRaymap({"simulate", std::string(RAYMAP_SCENES_DIR) + "/stairs_depth.yaml",
                                 "--rays", "depth.ply", "-q"});
  ASSERT_EQ(r.exit_code, 0) << describe(r);
  g.run({"populate", "depth.ply", "--max-range", "2", "-o", "depth.rmap", "-q"}, {"depth.rmap"});
}

TEST(GoldenOutputs, BagsOfLidarCloudsWithOdometryOrTfAndOfDepthImages) {
  REQUIRE_NODE_HARNESS();
  Golden g("bag");
  const Drive odometry = makeDrive(g.dir(), DrivePoses::kOdometry, 6);
  writeBag(odometry.spec, "odometry_bag", {"--compression", "zstd"});
  g.run({"populate", "odometry_bag", "-o", "odometry.rmap", "-q"}, {"odometry.rmap"});
  g.run({"heightmap", "odometry.rmap", "--center", "0,0,0", "--size", "8", "--csv",
         "odometry_heights.csv", "-q"},
        {"odometry_heights.csv"});

  TempDir tf_dir;
  const Drive tf = makeDrive(tf_dir, DrivePoses::kTfChain, 6);
  writeBag(tf.spec, "tf_bag", {"--storage", "sqlite3"});
  g.run({"populate", "tf_bag", "--pose-source", "tf", "--world-frame", "map", "--semantics", "scan",
         "-o", "tf.rmap", "-q"},
        {"tf.rmap"});

  TempDir depth_dir;
  const DepthBag depth = makeDepthBag(depth_dir, 6, true, true);
  writeBag(depth.spec, "depth_bag", {});
  g.run({"populate", "depth_bag", "--max-range", "3", "--downsample", "2", "--invalid-as-free",
         "-o", "depth.rmap", "-q"},
        {"depth.rmap"});
}

/// The files of the shared data set called `name`; `missing` says why they cannot be used.
DataFiles sharedData(const std::string& name) {
  for (const DataSet& set : sharedDataSets()) {
    if (name == set.name) {
      return dataFiles(set);
    }
  }
  return DataFiles{{}, {}, "no data set " + name};
}

TEST(GoldenOutputs, SharedOusterScanInEveryMode) {
  const DataFiles ouster = sharedData("ouster");
  if (!ouster.missing.empty()) {
    GTEST_SKIP() << ouster.missing;
  }
  Golden g("ouster");
  const std::string in = g.link(ouster.file, "ouster.ply.gz");
  g.run({"populate", in, "-o", "ray.rmap", "-q"}, {"ray.rmap"});
  g.run({"populate", in, "--semantics", "scan", "-o", "scan.rmap", "-q"}, {"scan.rmap"});
  g.run({"populate", in, "--mode", "ndt-om", "--max-range", "30", "-o", "ndt_om.rmap", "-q"},
        {"ndt_om.rmap"});
  g.run({"populate", in, "--mode", "tsdf", "-o", "tsdf.rmap", "-q"}, {"tsdf.rmap"});
  g.run({"export", "ray.rmap", "--ply", "occupied.ply"}, {"occupied.ply"});
  g.run({"heightmap", "ray.rmap", "--center", "0,0,0", "--size", "20", "--csv", "heights.csv",
         "--png", "heights.png", "-q"},
        {"heights.csv", "heights.png"});
}

TEST(GoldenOutputs, SharedOctomapAnd3dtkScans) {
  const DataFiles octomap = sharedData("octomap");
  const DataFiles points = sharedData("3dtk_points");
  for (const DataFiles* files : {&octomap, &points}) {
    if (!files->missing.empty()) {
      GTEST_SKIP() << files->missing;
    }
  }
  Golden g("shared");
  g.run({"populate", g.link(octomap.file, "octomap.ply.gz"), "-o", "octomap.rmap", "-q"},
        {"octomap.rmap"});
  g.run({"populate", g.link(points.file, "3dtk_points.ply.gz"), "--trajectory",
         g.link(points.trajectory, "3dtk_trajectory.txt"), "-o", "3dtk_points.rmap", "-q"},
        {"3dtk_points.rmap"});
}

}  // namespace
}  // namespace raymap::test
