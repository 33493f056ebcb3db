// SPDX-License-Identifier: BSD-3-Clause
// `raymap simulate` end to end: its recordings map with `raymap populate` (ray cloud, and points
// with their trajectory), the true height field it writes, determinism, and its errors.
#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "tests/support/cli_runner.hpp"
#include "tests/support/json_doc.hpp"
#include "tests/support/temp_dir.hpp"

namespace raymap::test {
namespace {

namespace fs = std::filesystem;

/// A number in the stats JSON `populate --stats-json -` prints (NaN, and a test failure, when
/// it has none by that name).
double statsValue(const std::string& json, const std::string& key) {
  const std::optional<Json> document = parseJson(json);
  const Json* value = document ? findFirst(*document, key) : nullptr;
  if (value == nullptr || !value->is_number()) {
    ADD_FAILURE() << key << " not a number in " << json;
    return std::nan("");
  }
  return value->get<double>();
}

/// The counts of the summary line "simulated NAME: S scans, R rays, N no-return -> ...".
struct Summary {
  std::uint64_t scans = 0;
  std::uint64_t rays = 0;
  std::uint64_t no_return = 0;
};

std::optional<Summary> parseSummary(std::string line) {
  std::string digits;
  for (char c : line) {
    if (c != ',') {
      digits += c;
    }
  }
  Summary s;
  unsigned long long scans = 0;
  unsigned long long rays = 0;
  unsigned long long no_return = 0;
  const std::size_t colon = digits.find(": ");
  if (colon == std::string::npos ||
      std::sscanf(digits.c_str() + colon + 2, "%llu scans %llu rays %llu no-return", &scans, &rays,
                  &no_return) != 3) {
    return std::nullopt;
  }
  s.scans = scans;
  s.rays = rays;
  s.no_return = no_return;
  return s;
}

/// The truth CSV as (x, y) rounded to millimetres -> "height,clearance".
std::map<std::pair<long, long>, std::string> readTruth(const std::string& path) {
  std::map<std::pair<long, long>, std::string> cells;
  std::istringstream in(readFile(path));
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line, "x,y,height,clearance");
  while (std::getline(in, line)) {
    const std::size_t c1 = line.find(',');
    const std::size_t c2 = line.find(',', c1 + 1);
    const double x = std::stod(line.substr(0, c1));
    const double y = std::stod(line.substr(c1 + 1, c2 - c1 - 1));
    cells[{std::lround(x * 1000.0), std::lround(y * 1000.0)}] = line.substr(c2 + 1);
  }
  return cells;
}

std::string cell(const std::map<std::pair<long, long>, std::string>& truth, double x, double y) {
  const auto at = truth.find({std::lround(x * 1000.0), std::lround(y * 1000.0)});
  return at == truth.end() ? "(no cell)" : at->second;
}

TEST(CliSimulate, RayCloudMapsWithPopulate) {
  TempDir dir;
  const std::string rays = dir.file("stairs.ply");

  const RunResult sim = runRaymap({"simulate", std::string(RAYMAP_SCENES_DIR) + "/stairs.yaml",
                                   "--rays", rays, "--scans", "3"});
  ASSERT_EQ(sim.exit_code, 0) << describe(sim);
  const std::optional<Summary> summary = parseSummary(sim.out);
  ASSERT_TRUE(summary.has_value()) << sim.out;
  EXPECT_EQ(summary->scans, 3u);
  EXPECT_EQ(summary->rays, 3u * 32u * 1024u);  // stairs.yaml: 32 beams, 1024 columns
  EXPECT_NE(sim.out.find("-> " + rays), std::string::npos) << sim.out;

  const RunResult pop =
      runRaymap({"populate", rays, "--max-range", "20", "--stats-json", "-", "-q"});

  ASSERT_EQ(pop.exit_code, 0) << describe(pop);
  EXPECT_EQ(statsValue(pop.out, "rays_in"), static_cast<double>(summary->rays));
  EXPECT_EQ(statsValue(pop.out, "rays_no_return"), static_cast<double>(summary->no_return));
  EXPECT_EQ(statsValue(pop.out, "rays_rejected"), 0.0);
  EXPECT_EQ(statsValue(pop.out, "scans"), 3.0);
  EXPECT_GT(statsValue(pop.out, "voxels_occupied"), 1000.0);
}

TEST(CliSimulate, PointsWithTrajectoryMapWithPopulate) {
  TempDir dir;
  const std::string rays = dir.file("rays.ply");
  const std::string points = dir.file("points.ply");
  const std::string trajectory = dir.file("trajectory.txt");

  const RunResult sim =
      runRaymap({"simulate", std::string(RAYMAP_SCENES_DIR) + "/stairs.yaml", "--rays", rays,
                 "--points", points, "--trajectory", trajectory, "--scans", "3", "--seed", "5"});
  ASSERT_EQ(sim.exit_code, 0) << describe(sim);
  const std::optional<Summary> summary = parseSummary(sim.out);
  ASSERT_TRUE(summary.has_value()) << sim.out;
  // The trajectory has one pose per column: 3 scans x 1024 columns and a header line.
  const std::string text = readFile(trajectory);
  EXPECT_EQ(std::count(text.begin(), text.end(), '\n'), 3 * 1024 + 1);
  EXPECT_EQ(text.rfind("# time x y z qw qx qy qz\n", 0), 0u);

  const RunResult from_points = runRaymap({"populate", points, "--trajectory", trajectory,
                                           "--max-range", "20", "--stats-json", "-", "-q"});
  const RunResult from_rays =
      runRaymap({"populate", rays, "--max-range", "20", "--stats-json", "-", "-q"});

  ASSERT_EQ(from_points.exit_code, 0) << describe(from_points);
  ASSERT_EQ(from_rays.exit_code, 0) << describe(from_rays);
  // Points are the returns; each one's origin comes from the trajectory.
  EXPECT_EQ(statsValue(from_points.out, "rays_in"),
            static_cast<double>(summary->rays - summary->no_return));
  EXPECT_EQ(statsValue(from_points.out, "rays_rejected"), 0.0);
  EXPECT_EQ(statsValue(from_points.out, "scans"), 3.0);
  // The same surfaces: the ray cloud's no-return rays only clear a few more voxels.
  const double occupied_points = statsValue(from_points.out, "voxels_occupied");
  const double occupied_rays = statsValue(from_rays.out, "voxels_occupied");
  EXPECT_NEAR(occupied_points, occupied_rays, 0.01 * occupied_rays);
}

TEST(CliSimulate, TruthCsvHoldsTheDitchAndItsSides) {
  TempDir dir;
  const std::string csv = dir.file("truth.csv");

  const RunResult sim = runRaymap({"simulate", std::string(RAYMAP_SCENES_DIR) + "/ditch.yaml",
                                   "--truth", csv, "--truth-box", "1.5,-0.5,3.5,0.5"});

  ASSERT_EQ(sim.exit_code, 0) << describe(sim);
  EXPECT_NE(sim.out.find("(200 cells)"), std::string::npos) << sim.out;
  const auto truth = readTruth(csv);
  EXPECT_EQ(truth.size(), 200u);  // 20 x 10 cells of 0.1 m
  EXPECT_EQ(cell(truth, 2.55, 0.05), "-0.8,inf");
  EXPECT_EQ(cell(truth, 1.55, 0.05), "0,inf");
  EXPECT_EQ(cell(truth, 3.45, -0.45), "0,inf");
}

TEST(CliSimulate, TruthUnderATableDependsOnTheClearance) {
  TempDir dir;
  const std::string low = dir.file("low.csv");
  const std::string high = dir.file("high.csv");
  const std::string room = std::string(RAYMAP_SCENES_DIR) + "/room.yaml";

  ASSERT_EQ(runRaymap({"simulate", room, "--truth", low, "-q"}).exit_code, 0);
  ASSERT_EQ(
      runRaymap({"simulate", room, "--truth", high, "--min-clearance", "1.0", "-q"}).exit_code, 0);

  // room.yaml: the table top spans x 0.2..1.8, y 0.05..0.95, from 0.71 to 0.75 m; the ceiling
  // is at 2.5 m.
  const auto under_low = readTruth(low);
  const auto under_high = readTruth(high);
  EXPECT_EQ(cell(under_low, 1.05, 0.55), "0,0.71");
  EXPECT_EQ(cell(under_high, 1.05, 0.55), "0.75,1.75");
  EXPECT_EQ(cell(under_low, -1.05, -1.05), "0,2.5");
}

TEST(CliSimulate, TruthCellsWithoutSurfaceAreEmpty) {
  TempDir dir;
  const std::string scene = dir.file("floating.yaml");
  std::ofstream(scene) << "ground: none\n"
                          "objects:\n"
                          "  - {type: box, min: [0, 0, 1], max: [1, 1, 2]}\n"
                          "trajectory: {waypoints: [[0.5, 0.5, 3]], speed: 1}\n"
                          "scans: 1\n";
  const std::string csv = dir.file("truth.csv");

  const RunResult sim =
      runRaymap({"simulate", scene, "--truth", csv, "--truth-box", "-1,0,1,0.1", "-q"});

  ASSERT_EQ(sim.exit_code, 0) << describe(sim);
  const auto truth = readTruth(csv);
  EXPECT_EQ(truth.size(), 20u);
  EXPECT_EQ(cell(truth, -0.05, 0.05), ",");
  EXPECT_EQ(cell(truth, 0.05, 0.05), "2,inf");
}

TEST(CliSimulate, SameSeedSameFileOtherSeedOtherFile) {
  TempDir dir;
  const std::string scene = std::string(RAYMAP_SCENES_DIR) + "/ditch.yaml";
  const std::string a = dir.file("a.ply");
  const std::string b = dir.file("b.ply");
  const std::string c = dir.file("c.ply");

  ASSERT_EQ(runRaymap({"simulate", scene, "--rays", a, "--scans", "2", "-q"}).exit_code, 0);
  ASSERT_EQ(runRaymap({"simulate", scene, "--rays", b, "--scans", "2", "-q"}).exit_code, 0);
  ASSERT_EQ(
      runRaymap({"simulate", scene, "--rays", c, "--scans", "2", "--seed", "99", "-q"}).exit_code,
      0);

  EXPECT_TRUE(readFile(a) == readFile(b));
  EXPECT_EQ(readFile(a).size(), readFile(c).size());
  EXPECT_FALSE(readFile(a) == readFile(c));
}

TEST(CliSimulate, BadSceneFileNamesTheKeyAndWritesNothing) {
  TempDir dir;
  const std::string scene = dir.file("bad.yaml");
  std::ofstream(scene) << "objects:\n"
                          "  - {type: pole, at: [0, 0], radius: -0.1, height: 2}\n"
                          "trajectory: {waypoints: [[0, 0, 1], [1, 0, 1]], speed: 1}\n";

  const RunResult sim =
      runRaymap({"simulate", scene, "--rays", dir.file("out.ply"), "--truth", dir.file("out.csv")});

  EXPECT_EQ(sim.exit_code, 1);
  EXPECT_NE(sim.err.find("raymap simulate: error: " + scene +
                         ": line 2: objects[0].radius: must be > 0 (got -0.1)"),
            std::string::npos)
      << sim.err;
  for (const auto& entry : fs::directory_iterator(dir.path())) {
    EXPECT_EQ(entry.path().filename(), "bad.yaml") << "left behind: " << entry.path();
  }
}

TEST(CliSimulate, UsageErrors) {
  TempDir dir;
  const std::string scene = std::string(RAYMAP_SCENES_DIR) + "/room.yaml";

  const RunResult nothing = runRaymap({"simulate", scene});
  const RunResult points_alone = runRaymap({"simulate", scene, "--points", dir.file("p.ply")});
  const RunResult bad_box =
      runRaymap({"simulate", scene, "--truth", dir.file("t.csv"), "--truth-box", "1,1,0,2"});

  EXPECT_EQ(nothing.exit_code, 2) << describe(nothing);
  EXPECT_NE(nothing.err.find("nothing to write"), std::string::npos) << nothing.err;
  EXPECT_EQ(points_alone.exit_code, 2) << describe(points_alone);
  EXPECT_NE(points_alone.err.find("--points and --trajectory go together"), std::string::npos);
  EXPECT_EQ(bad_box.exit_code, 2) << describe(bad_box);
  EXPECT_NE(bad_box.err.find("--truth-box: '1,1,0,2'"), std::string::npos) << bad_box.err;
  EXPECT_TRUE(fs::is_empty(dir.path()));
}

}  // namespace
}  // namespace raymap::test
