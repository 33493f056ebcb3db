// SPDX-License-Identifier: BSD-3-Clause
// Outlier returns (issue 52, M4): one ghost return tens of kilometres away is counted and left
// out by --max-ray-length, never fatal, and cannot grow the map, whatever its memory budget.
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "tests/support/cli_runner.hpp"
#include "tests/support/temp_dir.hpp"
#include "tests/support/test_rays.hpp"

namespace raymap::test {
namespace {

/// A 20 m corridor drive, and the same with one return 35 km away in the middle of it.
struct OutlierClouds {
  TempDir dir;
  std::string clean = dir.file("clean.ply");
  std::string ghost = dir.file("ghost.ply");
  OutlierClouds() {
    std::vector<Ray> rays = corridorDrive(20.0, 0.5);
    writeRayCloud(clean, rays);
    Ray far = rays[rays.size() / 2];
    far.sample = Vec3d{far.origin.x + 35000.0, far.origin.y + 1200.0, far.origin.z + 40.0};
    rays.insert(rays.begin() + static_cast<std::ptrdiff_t>(rays.size() / 2), far);
    writeRayCloud(ghost, rays);
  }
};

/// `raymap info --json`'s "regions" of `map` (-1 when the command fails).
long regionsOf(const std::string& map) {
  const RunResult info = runRaymap({"info", map, "--json"});
  const std::optional<std::string> regions =
      info.exit_code == 0 ? jsonValue(info.out, "regions") : std::nullopt;
  if (!regions) {
    ADD_FAILURE() << describe(info);
    return -1;
  }
  return std::stol(*regions);
}

TEST(CliOutliers, AReturnThirtyFiveKilometresAwayIsCountedAndLeftOutNotMapped) {
  const OutlierClouds clouds;
  const std::string clean = clouds.dir.file("clean.rmap");
  const std::string ghost = clouds.dir.file("ghost.rmap");
  ASSERT_EQ(runRaymap({"populate", clouds.clean, "-o", clean, "--quiet"}).exit_code, 0);
  const RunResult r = runRaymap({"populate", clouds.ghost, "-o", ghost});
  ASSERT_EQ(r.exit_code, 0) << describe(r);
  EXPECT_TRUE(contains(r.out, "out of bounds or longer than --max-ray-length 1)")) << r.out;
  EXPECT_EQ(regionsOf(ghost), regionsOf(clean)) << "the ghost ray grew the map";
}

TEST(CliOutliers, AnOutlierIsNotFatalThroughASmallMemoryBudget) {
  // Before: "one batch touches more regions than the pool's N hold at once; raise --max-memory".
  const OutlierClouds clouds;
  const std::string out = clouds.dir.file("small.rmap");
  const RunResult r =
      runRaymap({"populate", clouds.ghost, "-o", out, "--max-memory", "8MiB", "--compressed-memory",
                 "256KiB", "--region-voxels", "16", "--quiet"});
  ASSERT_EQ(r.exit_code, 0) << describe(r);
  EXPECT_GT(regionsOf(out), 0);
  // Without the rule the ray goes in (the batches split themselves to fit the pool: issue 52,
  // M8; before, this run ended there), and it costs the map thousands of regions.
  const std::string unlimited = clouds.dir.file("unlimited.rmap");
  const RunResult without = runRaymap({"populate", clouds.ghost, "-o", unlimited, "--max-memory",
                                       "8MiB", "--compressed-memory", "256KiB", "--region-voxels",
                                       "16", "--max-ray-length", "0", "--quiet"});
  ASSERT_EQ(without.exit_code, 0) << describe(without);
  EXPECT_GT(regionsOf(unlimited), 10 * regionsOf(out));
}

TEST(CliOutliers, MaxRayLengthIsCheckedAgainstMinRange) {
  const OutlierClouds clouds;
  const std::string out = clouds.dir.file("never.rmap");
  const RunResult r =
      runRaymap({"populate", clouds.clean, "-o", out, "--min-range", "5", "--max-ray-length", "2"});
  EXPECT_NE(r.exit_code, 0);
  EXPECT_TRUE(contains(r.err, "--max-ray-length must be larger than --min-range")) << describe(r);
  EXPECT_FALSE(std::filesystem::exists(out));
}

}  // namespace
}  // namespace raymap::test
