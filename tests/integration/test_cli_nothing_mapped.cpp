// SPDX-License-Identifier: BSD-3-Clause
// A populate that integrates no ray fails (issue 52, L10): an empty map is never a result, the
// reasons are counted in the error, and no output is left behind.
#include <filesystem>

#include <gtest/gtest.h>

#include "tests/support/cli_runner.hpp"
#include "tests/support/temp_dir.hpp"
#include "tests/support/test_rays.hpp"

namespace raymap::test {
namespace {

TEST(CliNothingMapped, APopulateThatRejectsEveryRayFailsNamingWhyAndWritesNothing) {
  TempDir dir;
  const std::string input = dir.file("rays.ply");
  writeRayCloud(input, corridorDrive(20.0, 0.5));
  const std::string map = dir.file("empty.rmap");
  const std::string stats = dir.file("stats.json");
  const RunResult r =
      runRaymap({"populate", input, "--min-range", "100", "-o", map, "--stats-json", stats});
  EXPECT_EQ(r.exit_code, 1) << describe(r);
  EXPECT_TRUE(contains(r.err, "no ray of " + input + " was integrated"));
  EXPECT_TRUE(contains(r.err, "all rejected (invalid 0, too short "));
  EXPECT_TRUE(contains(r.err, "--min-range 100 m"));
  EXPECT_FALSE(std::filesystem::exists(map));
  EXPECT_FALSE(std::filesystem::exists(stats));
  // The same rays with the default range limits are mapped.
  EXPECT_EQ(runRaymap({"populate", input, "-o", map, "-q"}).exit_code, 0);
  EXPECT_TRUE(std::filesystem::exists(map));
}

}  // namespace
}  // namespace raymap::test
