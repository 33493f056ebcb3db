// SPDX-License-Identifier: BSD-3-Clause
// `raymap populate BAG`: rosbag2 recordings written by Foxglove's MCAP library and ROS 2
// serializer (independent of raymap) map to the same voxels as the same rays in a PLY, in every
// storage (MCAP uncompressed, zstd, lz4, chunked or not, indexed or not; SQLite), and the map
// matches the simulated scene's truth.
#include <cstdint>
#include <optional>

#include <gtest/gtest.h>

#include "tests/replay/replay_harness.hpp"
#include "tests/rosbag/bag_fixture.hpp"
#include "tests/support/json_doc.hpp"
#include "tests/support/scene_truth.hpp"

namespace raymap::test {
namespace {

struct Counts {
  double free = -1;
  double occupied = -1;
  double rays = -1;
};

Counts populate(const TempDir& dir, const std::string& input,
                const std::vector<std::string>& extra = {}) {
  static int run = 0;
  const std::string stats = dir.file("stats" + std::to_string(run++) + ".json");
  std::vector<std::string> args{"populate", input, "--stats-json", stats, "-q"};
  args.insert(args.end(), extra.begin(), extra.end());
  const RunResult r = runRaymap(args);
  EXPECT_EQ(r.exit_code, 0) << describe(r);
  const std::string json = readFile(stats);
  Counts c;
  c.free = jsonNumber(json, "voxels_free").value_or(-1);
  c.occupied = jsonNumber(json, "voxels_occupied").value_or(-1);
  c.rays = jsonNumber(json, "rays_integrated").value_or(-1);
  return c;
}

TEST(BagPopulate, EveryStorageGivesTheVoxelsOfTheSameRaysInAPly) {
  REQUIRE_NODE_HARNESS();
  TempDir dir;
  const Drive drive = makeDrive(dir, DrivePoses::kOdometry, 12);
  const Counts ply = populate(dir, drive.ply);
  ASSERT_GT(ply.occupied, 100.0);
  ASSERT_EQ(ply.rays, static_cast<double>(drive.rays));

  const std::vector<std::pair<std::string, std::vector<std::string>>> variants = {
      {"plain", {}},
      {"zstd", {"--compression", "zstd"}},
      {"lz4", {"--compression", "lz4", "--chunk-size", "65536"}},
      {"unchunked", {"--chunk-size", "0"}},
      {"unindexed", {"--compression", "zstd", "--unindexed"}},
      {"sqlite", {"--storage", "sqlite3"}},
  };
  for (const auto& [name, options] : variants) {
    SCOPED_TRACE(name);
    const std::string bag = dir.file("bag_" + name);
    writeBag(drive.spec, bag, options);
    const Counts c = populate(dir, bag);
    EXPECT_EQ(c.rays, ply.rays);
    EXPECT_EQ(c.free, ply.free);
    EXPECT_EQ(c.occupied, ply.occupied);
  }
  // A single file works as well as the directory.
  const std::string file = dir.file("single.mcap");
  writeBag(drive.spec, file, {"--file-only"});
  const Counts single = populate(dir, file);
  EXPECT_EQ(single.occupied, ply.occupied);
  EXPECT_EQ(single.free, ply.free);
}

TEST(BagPopulate, PosesFromATfChainGiveTheSameMapAsOdometry) {
  REQUIRE_NODE_HARNESS();
  TempDir dir;
  const Drive drive = makeDrive(dir, DrivePoses::kTfChain, 12);
  const Counts ply = populate(dir, drive.ply);
  const std::string bag = dir.file("tf_bag");
  writeBag(drive.spec, bag, {"--compression", "zstd"});
  const Counts c = populate(dir, bag, {"--pose-source", "tf", "--world-frame", "map"});
  EXPECT_EQ(c.rays, ply.rays);
  EXPECT_EQ(c.free, ply.free);
  EXPECT_EQ(c.occupied, ply.occupied);
}

TEST(BagPopulate, TheMapFromABagMatchesTheScenesTruth) {
  REQUIRE_NODE_HARNESS();
  TempDir dir;
  const Drive drive = makeDrive(dir, DrivePoses::kOdometry, 20);
  const std::string bag = dir.file("truth_bag");
  writeBag(drive.spec, bag, {});
  const OfflineHeights heights =
      offlineHeights(dir, bag, {}, drive.centre.x, drive.centre.y, 0.0, 16.0);
  int compared = 0;
  int within = 0;
  for (const auto& [key, cell] : heights) {
    if (!cell.surface) {
      continue;
    }
    const Vec3d centre{(static_cast<double>(key.first) + 0.5) * 0.1,
                       (static_cast<double>(key.second) + 0.5) * 0.1, 0.0};
    const auto truth = unambiguousTruth(drive.scene, centre, 0.1, 0.0, 0.5);
    if (!truth) {
      continue;
    }
    ++compared;
    within += std::fabs(static_cast<double>(cell.elevation) - truth->height) <= 0.1 ? 1 : 0;
  }
  ASSERT_GT(compared, 500);
  EXPECT_GT(static_cast<double>(within) / compared, 0.9)
      << within << " of " << compared << " surface cells within a voxel of the truth";
}

}  // namespace
}  // namespace raymap::test

namespace raymap::test {
namespace {

TEST(BagInfo, CountsFromAnMcapSummaryAgreeWithReadingEveryMessage) {
  REQUIRE_NODE_HARNESS();
  TempDir dir;
  const Drive drive = makeDrive(dir, DrivePoses::kOdometry, 4);
  const std::string indexed = dir.file("indexed.mcap");
  const std::string unindexed = dir.file("unindexed.mcap");
  writeBag(drive.spec, indexed, {"--file-only", "--compression", "zstd"});
  writeBag(drive.spec, unindexed, {"--file-only", "--unindexed"});
  const RunResult summary = runRaymap({"info", indexed, "--json"});
  const RunResult all = runRaymap({"info", indexed, "--json", "--read-all"});
  const RunResult plain = runRaymap({"info", unindexed, "--json"});
  for (const RunResult* r : {&summary, &all, &plain}) {
    ASSERT_EQ(r->exit_code, 0) << describe(*r);
  }
  EXPECT_EQ(jsonValue(summary.out, "counted_from"), "summary") << summary.out;
  EXPECT_EQ(jsonValue(all.out, "counted_from"), "messages") << all.out;
  EXPECT_EQ(jsonValue(plain.out, "counted_from"), "messages") << plain.out;
  for (const char* key : {"messages", "start_ns", "end_ns"}) {
    EXPECT_EQ(jsonNumber(summary.out, key), jsonNumber(all.out, key)) << key;
    EXPECT_EQ(jsonNumber(plain.out, key), jsonNumber(all.out, key)) << key;
  }
  // 4 clouds, the odometry around them and one /tf_static.
  EXPECT_EQ(jsonNumber(all.out, "messages").value_or(0), 4 + 1 + 51);
  // The messages of the clouds' topic in the list of topics.
  const auto clouds = [](const std::string& out) -> std::optional<std::int64_t> {
    const std::optional<Json> json = parseJson(out);
    const Json* topics = json ? findPath(*json, {"topics"}) : nullptr;
    for (const Json& topic : topics != nullptr ? *topics : Json::array()) {
      if (topic.value("name", "") == "/ouster/points") {
        return topic.value("messages", std::int64_t{-1});
      }
    }
    return std::nullopt;
  };
  EXPECT_EQ(clouds(summary.out), 4) << summary.out;
  EXPECT_EQ(clouds(all.out), 4) << all.out;
}

}  // namespace
}  // namespace raymap::test
