// SPDX-License-Identifier: BSD-3-Clause
// The command line over maps larger than --max-memory (docs/large-maps.md): populate, info,
// export and heightmap through a pool an eighth of the map give what unlimited memory gives, say
// where the regions went, and fail cleanly when the spill folder cannot be used.
#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "tests/support/cli_runner.hpp"
#include "tests/support/json_doc.hpp"
#include "tests/support/temp_dir.hpp"
#include "tests/support/test_rays.hpp"

namespace raymap::test {
namespace {

namespace fs = std::filesystem;

/// The drive (test::corridorDrive, 120 m) as a ray cloud in `dir`; regions of 16^3 voxels of
/// 0.1 m (384 regions of 48 KiB with the voxel mean), of which a scan touches about 60.
struct Drive {
  TempDir dir;
  std::string ply = dir.file("drive.ply");
  Drive() { writeRayCloud(ply, corridorDrive(120.0, 0.5)); }
};

const std::vector<std::string> kMapping = {"--region-voxels", "16", "--batch-rays", "1024",
                                           "--threads",       "1"};

/// A number in a JSON object (NaN, and a test failure, when it is not there).
double number(const Json& object, const std::string& key) {
  const Json* value = findPath(object, {key});
  EXPECT_TRUE(value != nullptr && value->is_number()) << key;
  return value != nullptr && value->is_number() ? value->get<double>() : std::nan("");
}

/// The document `text` (null, and a test failure, when it is not JSON).
Json parsed(const std::string& text) { return parseJson(text).value_or(Json()); }

Json member(const Json& object, const std::string& key) {
  const Json* value = findPath(object, {key});
  EXPECT_NE(value, nullptr) << key;
  return value != nullptr ? *value : Json();
}

std::vector<std::string> with(std::vector<std::string> a, const std::vector<std::string>& b) {
  a.insert(a.end(), b.begin(), b.end());
  return a;
}

TEST(CliLargeMaps, PopulateThroughAnEighthOfTheMemoryWritesTheSameMapAndSaysWhereRegionsWent) {
  const Drive drive;
  const std::string whole = drive.dir.file("whole.rmap");
  const std::string small = drive.dir.file("small.rmap");
  const RunResult a = runRaymap(with({"populate", drive.ply, "-o", whole, "--quiet"}, kMapping));
  ASSERT_EQ(a.exit_code, 0) << describe(a);
  const RunResult info = runRaymap({"info", whole, "--json"});
  ASSERT_EQ(info.exit_code, 0) << describe(info);
  const auto regions = static_cast<std::uint64_t>(number(parsed(info.out), "regions"));
  ASSERT_GT(regions, 300u);
  const std::uint64_t pool_bytes = regions / 8 * 16 * 16 * 16 * 12;  // occupancy + mean

  const std::string spill = drive.dir.file("spill");
  fs::create_directory(spill);
  const RunResult b =
      runRaymap(with({"populate", drive.ply, "-o", small, "--max-memory",
                      std::to_string(pool_bytes), "--compressed-memory", "64KiB", "--spill-dir",
                      spill, "--stats-json", drive.dir.file("stats.json")},
                     kMapping));
  ASSERT_EQ(b.exit_code, 0) << describe(b);
  EXPECT_EQ(readFile(small), readFile(whole));
  EXPECT_TRUE(contains(b.out, "memory tiers   pool "));
  const Json tiers = member(parsed(readFile(drive.dir.file("stats.json"))), "memory_tiers");
  EXPECT_EQ(number(tiers, "pool_regions"), static_cast<double>(regions / 8));
  EXPECT_GT(number(tiers, "regions_spilled"), 0.0);
  EXPECT_GT(number(tiers, "spill_bytes_written"), 0.0);
  EXPECT_GT(number(tiers, "compression_ratio"), 2.0);
  EXPECT_LE(number(tiers, "compressed_bytes"), 65536.0);
  EXPECT_TRUE(fs::is_empty(spill)) << "the spill file has no name and is gone with raymap";
}

TEST(CliLargeMaps, AnEighthOfTheMemoryWorksWithTheDefaultBatchOnOneThreadAndOnTwo) {
  // Issue 52, M8: with the default batch (32,768 rays, more regions than the pool holds) this
  // aborted: "one batch touches more regions than the pool's N hold at once".
  const Drive drive;
  const std::string whole = drive.dir.file("whole.rmap");
  ASSERT_EQ(
      runRaymap({"populate", drive.ply, "-o", whole, "--region-voxels", "16", "--quiet"}).exit_code,
      0);
  const RunResult info = runRaymap({"info", whole, "--json"});
  const auto regions = static_cast<std::uint64_t>(number(parsed(info.out), "regions"));
  const std::uint64_t pool_bytes = regions / 8 * 16 * 16 * 16 * 12;
  for (const char* threads : {"1", "2"}) {
    const std::string unlimited = drive.dir.file(std::string("whole-") + threads + ".rmap");
    ASSERT_EQ(runRaymap({"populate", drive.ply, "-o", unlimited, "--region-voxels", "16",
                         "--threads", threads, "--quiet"})
                  .exit_code,
              0);
    const std::string small = drive.dir.file(std::string("small-") + threads + ".rmap");
    const RunResult r = runRaymap({"populate", drive.ply, "-o", small, "--region-voxels", "16",
                                   "--threads", threads, "--max-memory", std::to_string(pool_bytes),
                                   "--compressed-memory", "64KiB"});
    ASSERT_EQ(r.exit_code, 0) << threads << " threads\n" << describe(r);
    EXPECT_EQ(readFile(small), readFile(unlimited)) << threads << " threads";
    EXPECT_TRUE(contains(r.out, "batches split to fit the pool")) << r.out;
  }
}

TEST(CliLargeMaps, InfoExportAndHeightmapReadAMapLargerThanTheirMemory) {
  const Drive drive;
  const std::string map = drive.dir.file("drive.rmap");
  ASSERT_EQ(runRaymap(with({"populate", drive.ply, "-o", map, "--quiet"}, kMapping)).exit_code, 0);
  const std::vector<std::string> small = {"--max-memory", "1MiB", "--compressed-memory", "64KiB"};

  const RunResult whole_info = runRaymap({"info", map, "--json"});
  const RunResult small_info = runRaymap(with({"info", map, "--json"}, small));
  ASSERT_EQ(small_info.exit_code, 0) << describe(small_info);
  const Json w = parsed(whole_info.out);
  const Json s = parsed(small_info.out);
  for (const char* key : {"regions", "voxels_free", "voxels_occupied", "voxels_unobserved"}) {
    EXPECT_EQ(number(s, key), number(w, key)) << key;
  }
  EXPECT_GT(number(member(s, "memory_tiers"), "evictions"), 0.0);
  EXPECT_EQ(number(member(s, "memory_tiers"), "pool_regions"), 21.0);  // 1 MiB / 48 KiB

  for (const char* mode : {"occupied", "free"}) {
    const std::string a = drive.dir.file(std::string("whole-") + mode + ".ply");
    const std::string b = drive.dir.file(std::string("small-") + mode + ".ply");
    ASSERT_EQ(runRaymap({"export", map, "--ply", a, "--mode", mode, "-q"}).exit_code, 0);
    const RunResult r = runRaymap(with({"export", map, "--ply", b, "--mode", mode, "-q"}, small));
    ASSERT_EQ(r.exit_code, 0) << describe(r);
    EXPECT_EQ(readFile(b), readFile(a)) << mode;
  }

  for (const char* centre : {"4,0,0.05", "100,0,0.05"}) {
    const std::string a = drive.dir.file("whole.csv");
    const std::string b = drive.dir.file("small.csv");
    const std::vector<std::string> args = {"heightmap", map,   "--center", centre,
                                           "--size",    "3.2", "-q"};
    ASSERT_EQ(runRaymap(with(args, {"--csv", a})).exit_code, 0);
    const RunResult r = runRaymap(with(with(args, {"--csv", b}), small));
    ASSERT_EQ(r.exit_code, 0) << describe(r);
    EXPECT_EQ(readFile(b), readFile(a)) << centre;
  }
}

TEST(CliLargeMaps, AnUnusableSpillFolderFailsBeforeAnyWorkAndLeavesNoOutput) {
  const Drive drive;
  const std::string out = drive.dir.file("out.rmap");
  const RunResult r = runRaymap(with({"populate", drive.ply, "-o", out, "--max-memory", "1MiB",
                                      "--spill-dir", drive.dir.file("missing")},
                                     kMapping));
  EXPECT_EQ(r.exit_code, 1) << describe(r);
  EXPECT_TRUE(contains(r.err, "cannot create a spill file in " + drive.dir.file("missing")));
  EXPECT_TRUE(contains(r.err, "(--spill-dir names a writable folder")) << r.err;
  EXPECT_FALSE(fs::exists(out));
  // --no-tiers keeps the old fixed-memory behaviour: a full pool is an error naming the budget.
  const RunResult fixed = runRaymap(
      with({"populate", drive.ply, "-o", out, "--max-memory", "1MiB", "--no-tiers"}, kMapping));
  EXPECT_EQ(fixed.exit_code, 1) << describe(fixed);
  EXPECT_TRUE(contains(fixed.err, "--max-memory"));
  EXPECT_FALSE(fs::exists(out));
}

}  // namespace
}  // namespace raymap::test
