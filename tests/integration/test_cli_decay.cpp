// SPDX-License-Identifier: BSD-3-Clause
// Decay-rate maps through the raymap program: populate --mode decay (decay rates only) and
// --decay-rate with occupancy or an NDT mode, info, export --mode decay --threshold, and the
// errors for maps without the layer.
#include <fstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "tests/support/cli_runner.hpp"
#include "tests/support/temp_dir.hpp"
#include "tests/support/test_rays.hpp"

namespace raymap::test {
namespace {

/// Rays along +x from the centre of voxel (0,0,0) to x = 1.55, 1.65, 2.35, 1.03 and 1.07 m: at
/// 0.1 m, 24 voxels are entered and three have a rate of at least 4.5 per metre (voxel 10: 2
/// samples over 0.4 m; 16: 1 over 0.15 m; 23: 1 over 0.05 m).
void writeRays(const std::string& path) {
  std::vector<Ray> rays;
  for (const double end_x : {1.55, 1.65, 2.35, 1.03, 1.07}) {
    Ray ray;
    ray.origin = Vec3d{0.05, 0.05, 0.05};
    ray.sample = Vec3d{end_x, 0.05, 0.05};
    rays.push_back(ray);
  }
  writeRayCloud(path, rays);
}

TEST(CliDecay, PopulateInfoAndExportADecayRateMap) {
  TempDir dir;
  const std::string rays = dir.file("rays.ply");
  const std::string map = dir.file("decay.rmap");
  const std::string ply = dir.file("decay.ply");
  writeRays(rays);

  const RunResult populated = runRaymap(
      {"populate", rays, "--output", map, "--mode", "decay", "--resolution", "0.1", "--quiet"});
  ASSERT_EQ(populated.exit_code, 0) << describe(populated);
  const RunResult info = runRaymap({"info", map});
  ASSERT_EQ(info.exit_code, 0) << describe(info);
  EXPECT_TRUE(contains(info.out, "mode           decay\n")) << info.out;
  EXPECT_TRUE(contains(info.out, "traversal (4 B)")) << info.out;
  // Decay rates only: no occupancy layer, parameters or voxel counts.
  EXPECT_FALSE(contains(info.out, "occupancy (4 B)")) << info.out;
  EXPECT_FALSE(contains(info.out, "occupancy      hit")) << info.out;
  EXPECT_TRUE(contains(info.out, "decay voxels   24 crossed, 4 with samples")) << info.out;
  const RunResult occupied = runRaymap({"export", map, "--mode", "occupied", "--ply", ply});
  EXPECT_NE(occupied.exit_code, 0);
  EXPECT_TRUE(contains(occupied.err, "no occupancy layer")) << occupied.err;
  const RunResult exported =
      runRaymap({"export", map, "--mode", "decay", "--threshold", "4.5", "--ply", ply});
  ASSERT_EQ(exported.exit_code, 0) << describe(exported);
  EXPECT_TRUE(contains(exported.out, "wrote 3 points (decay)")) << exported.out;
  const std::string text = readFile(ply);
  EXPECT_TRUE(contains(text, "element vertex 3\n"));
  EXPECT_TRUE(contains(text, "property float decay_rate\n"));
}

TEST(CliDecay, DecayRateCombinesWithOccupancyAndNdt) {
  TempDir dir;
  const std::string rays = dir.file("rays.ply");
  writeRays(rays);
  for (const std::string mode : {"occupancy", "ndt-om"}) {
    const std::string map = dir.file(mode + ".rmap");
    const RunResult populated =
        runRaymap({"populate", rays, "--output", map, "--mode", mode, "--decay-rate", "--quiet"});
    ASSERT_EQ(populated.exit_code, 0) << describe(populated);
    const RunResult info = runRaymap({"info", map});
    EXPECT_TRUE(contains(info.out, "mode           " + mode + "+decay\n")) << info.out;
    EXPECT_TRUE(contains(info.out, "occupancy (4 B)")) << info.out;
    EXPECT_TRUE(contains(info.out, "decay voxels   24 crossed, 4 with samples")) << info.out;
  }
  // The name info prints is also a --mode.
  const std::string map = dir.file("named.rmap");
  const RunResult named =
      runRaymap({"populate", rays, "--output", map, "--mode", "occupancy+decay", "--quiet"});
  ASSERT_EQ(named.exit_code, 0) << describe(named);
  EXPECT_TRUE(contains(runRaymap({"info", map}).out, "mode           occupancy+decay\n"));
}

TEST(CliDecay, DecayRateKeepsTheModeOfAConfigFile) {
  // --decay-rate adds decay rates to the mode a --config file names; it used to reset the mode
  // to occupancy (the flag re-applied --mode's default).
  TempDir dir;
  const std::string rays = dir.file("rays.ply");
  writeRays(rays);
  const std::string yaml = dir.file("robot.yaml");
  {
    std::ofstream out(yaml);
    out << "map:\n  mode: ndt-om\n";
  }
  const std::string map = dir.file("ndt.rmap");
  const RunResult populated =
      runRaymap({"populate", rays, "--config", yaml, "--decay-rate", "--output", map, "--quiet"});
  ASSERT_EQ(populated.exit_code, 0) << describe(populated);
  const RunResult info = runRaymap({"info", map});
  EXPECT_TRUE(contains(info.out, "mode           ndt-om+decay\n")) << info.out;
}

TEST(CliDecay, ErrorsNameTheMapAndTheReason) {
  TempDir dir;
  const std::string rays = dir.file("rays.ply");
  const std::string map = dir.file("plain.rmap");
  writeRays(rays);
  ASSERT_EQ(runRaymap({"populate", rays, "--output", map, "--quiet"}).exit_code, 0);
  const RunResult no_layer =
      runRaymap({"export", map, "--mode", "decay", "--ply", dir.file("x.ply")});
  EXPECT_NE(no_layer.exit_code, 0);
  EXPECT_TRUE(contains(no_layer.err, map)) << no_layer.err;
  EXPECT_TRUE(contains(no_layer.err, "no traversal layer")) << no_layer.err;
  const RunResult wrong_mode = runRaymap(
      {"export", map, "--mode", "occupied", "--threshold", "2", "--ply", dir.file("y.ply")});
  EXPECT_NE(wrong_mode.exit_code, 0);
  EXPECT_TRUE(contains(wrong_mode.err, "--threshold applies only to --mode decay"))
      << wrong_mode.err;
  const RunResult no_mean =
      runRaymap({"populate", rays, "--output", dir.file("z.rmap"), "--mode", "decay", "--no-mean"});
  EXPECT_NE(no_mean.exit_code, 0);
  EXPECT_TRUE(contains(no_mean.err, "voxel mean")) << no_mean.err;
  const RunResult per_scan = runRaymap(
      {"populate", rays, "--output", dir.file("s.rmap"), "--mode", "decay", "--semantics", "scan"});
  EXPECT_NE(per_scan.exit_code, 0);
  EXPECT_TRUE(contains(per_scan.err, "--mode decay needs --semantics ray")) << per_scan.err;
  EXPECT_FALSE(contains(readFile(map), "traversal")) << "the plain map was not touched";
}

}  // namespace
}  // namespace raymap::test
