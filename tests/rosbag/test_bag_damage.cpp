// SPDX-License-Identifier: BSD-3-Clause
// Damaged and hostile bags (cut-off and corrupt files: test_bag_integrity.cpp): flipped bytes,
// unknown compression, a topic of the wrong type, a message that does not decode. Each gives a
// clear error or a counted skip naming the file, topic or message, never a crash or a wrong map;
// random damage is fuzzed through the reader in process.
#include <filesystem>
#include <fstream>
#include <random>

#include <gtest/gtest.h>

#include "src/bag/bag_reader.hpp"
#include "tests/rosbag/bag_fixture.hpp"
#include "tests/support/bag_spec.hpp"

namespace raymap::test {
namespace {

std::string bytesOf(const std::string& path) { return readFile(path); }

void writeAll(const std::string& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary) << bytes;
}

/// A small drive as one MCAP file with `options`.
std::string driveFile(const TempDir& dir, const std::string& name,
                      const std::vector<std::string>& options) {
  static int drives = 0;
  const Drive drive = makeDrive(dir, DrivePoses::kOdometry, 6);
  const std::string file = dir.file(name + std::to_string(drives++) + ".mcap");
  std::vector<std::string> all = options;
  all.push_back("--file-only");
  writeBag(drive.spec, file, all);
  return file;
}

TEST(BagDamage, AFlippedByteInAChunkFailsItsCrcAndLeavesNoMap) {
  REQUIRE_NODE_HARNESS();
  TempDir dir;
  const std::string file = driveFile(dir, "crc", {});
  std::string bytes = bytesOf(file);
  bytes[bytes.size() / 2] = static_cast<char>(bytes[bytes.size() / 2] ^ 0x5A);
  const std::string bad = dir.file("bad.mcap");
  writeAll(bad, bytes);
  const std::string map = dir.file("bad.rmap");
  const RunResult r = runRaymap({"populate", bad, "-o", map, "-q"});
  EXPECT_EQ(r.exit_code, 1) << describe(r);
  EXPECT_NE(r.err.find(bad), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("CRC"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(map));
}

TEST(BagDamage, AnUnknownChunkCompressionIsNamed) {
  REQUIRE_NODE_HARNESS();
  TempDir dir;
  const std::string file = driveFile(dir, "zstd", {"--compression", "zstd"});
  std::string bytes = bytesOf(file);
  // Every chunk header and chunk index names "zstd" (a uint32 length 4, then the text).
  const std::string zstd("\x04\x00\x00\x00zstd", 8);
  for (std::size_t at = bytes.find(zstd); at != std::string::npos; at = bytes.find(zstd, at)) {
    bytes.replace(at + 4, 4, "brot");
  }
  const std::string bad = dir.file("brotli.mcap");
  writeAll(bad, bytes);
  const RunResult r = runRaymap({"populate", bad, "-o", dir.file("b.rmap"), "-q"});
  EXPECT_EQ(r.exit_code, 1) << describe(r);
  EXPECT_NE(r.err.find("compression 'brot'"), std::string::npos) << r.err;
}

TEST(BagDamage, ATopicOfAnotherTypeAndAMessageThatDoesNotDecodeAreNamed) {
  REQUIRE_NODE_HARNESS();
  TempDir dir;
  const std::string spec = dir.file("odd.jsonl");
  {
    BagSpecWriter w(spec);
    w.channel("/odom", "nav_msgs/msg/Odometry");
    w.channel("/points", "sensor_msgs/msg/PointCloud2");
    w.channel("/imu_points", "nav_msgs/msg/Odometry");  // a topic named like a cloud
    for (int i = 0; i < 5; ++i) {
      const std::int64_t t = 1700000000000000000 + i * 100000000LL;
      w.odometry("/odom", t, t, "odom", "base_link", io::Pose{});
    }
    // A cloud whose data is shorter than row_step says.
    w.message("/points", 1700000000200000000,
              "{\"header\":{\"stamp\":{\"sec\":1700000000,\"nanosec\":100000000},\"frame_id\":"
              "\"base_link\"},\"height\":1,\"width\":4,\"fields\":[{\"name\":\"x\",\"offset\":0,"
              "\"datatype\":7,\"count\":1},{\"name\":\"y\",\"offset\":4,\"datatype\":7,"
              "\"count\":1},{\"name\":\"z\",\"offset\":8,\"datatype\":7,\"count\":1}],"
              "\"is_bigendian\":false,\"point_step\":12,\"row_step\":48,\"data\":{\"base64\":"
              "\"AACAPwAAAAAAAAAA\"},\"is_dense\":true}");
  }
  const std::string bag = dir.file("odd_bag");
  writeBag(spec, bag, {});
  const RunResult wrong =
      runRaymap({"populate", bag, "--topic", "/imu_points", "-o", dir.file("w.rmap"), "-q"});
  EXPECT_EQ(wrong.exit_code, 1) << describe(wrong);
  EXPECT_NE(wrong.err.find("'/imu_points'"), std::string::npos) << wrong.err;
  EXPECT_NE(wrong.err.find("nav_msgs/msg/Odometry, not sensor_msgs/msg/PointCloud2"),
            std::string::npos)
      << wrong.err;
  const RunResult missing =
      runRaymap({"populate", bag, "--topic", "/lidar", "-o", dir.file("m.rmap"), "-q"});
  EXPECT_EQ(missing.exit_code, 1) << describe(missing);
  EXPECT_NE(missing.err.find("/points"), std::string::npos)
      << "the error lists the PointCloud2 topics there are: " << missing.err;
  const RunResult bad =
      runRaymap({"populate", bag, "--pose-topic", "/odom", "-o", dir.file("b.rmap"), "-q"});
  EXPECT_EQ(bad.exit_code, 1) << "nothing could be mapped: " << describe(bad);
  EXPECT_NE(bad.err.find("on topic '/points' skipped: data_size_mismatch"), std::string::npos)
      << bad.err;
}

/// A small bag description: /tf_static, 10 Hz odometry and five 64-point clouds.
std::string smallSpec(const TempDir& dir) {
  const std::string spec = dir.file("small.jsonl");
  BagSpecWriter w(spec);
  w.channel("/tf_static", "tf2_msgs/msg/TFMessage");
  w.channel("/odom", "nav_msgs/msg/Odometry");
  w.channel("/points", "sensor_msgs/msg/PointCloud2");
  const std::int64_t t0 = 1700000000000000000;
  w.tf("/tf_static", t0, {{t0, "base_link", "lidar", io::Pose{{0.1, 0.0, 0.5}}}});
  const std::vector<msgs::ScanPoint> points = ringCloud(64);
  std::vector<std::uint16_t> rings(64, 0);
  for (int k = 0; k < 5; ++k) {
    const std::int64_t t = t0 + k * 100000000LL;
    w.odometry("/odom", t, t, "odom", "base_link", io::Pose{{0.1 * k, 0.0, 0.0}});
    w.ousterCloud("/points", t + 100000001, t, "lidar", points, rings);
  }
  const std::int64_t end = t0 + 500000000;
  w.odometry("/odom", end, end, "odom", "base_link", io::Pose{{0.5, 0.0, 0.0}});
  return spec;
}

/// Every pass over a damaged file ends: with the messages, or an error, never a crash.
void readThrough(const std::string& path) {
  auto bag = bag::openBag(path);
  if (!bag) {
    EXPECT_FALSE(bag.error().message.empty());
    return;
  }
  std::uint64_t bytes = 0;
  auto pass = bag.value()->forEach([&](const bag::BagMessage& m) {
    bytes += m.data.size();
    return true;
  });
  if (!pass) {
    EXPECT_NE(pass.error().message.find(path), std::string::npos) << pass.error().message;
  }
}

TEST(BagDamage, RandomDamageToMcapFilesNeverCrashesTheReader) {
  REQUIRE_NODE_HARNESS();
  TempDir dir;
  const std::string spec = smallSpec(dir);
  const std::vector<std::pair<std::string, std::vector<std::string>>> layouts = {
      {"plain", {"--chunk-size", "2000"}},
      {"zstd", {"--compression", "zstd", "--chunk-size", "2000"}},
      {"lz4", {"--compression", "lz4", "--chunk-size", "2000"}},
      {"flat", {"--chunk-size", "0", "--unindexed"}},
  };
  std::vector<std::string> files;
  for (const auto& [name, options] : layouts) {
    files.push_back(dir.file(name + ".mcap"));
    std::vector<std::string> all = options;
    all.push_back("--file-only");
    writeBag(spec, files.back(), all);
    auto whole = bag::openBag(files.back());
    ASSERT_TRUE(whole.has_value()) << whole.error().message;
    auto pass = whole.value()->forEach([](const bag::BagMessage&) { return true; });
    ASSERT_TRUE(pass.has_value()) << pass.error().message;
    ASSERT_EQ(pass.value().messages, 12u) << name;
  }
  // Under the sanitizers every read costs several times more: fewer rounds, still every layout.
#ifdef RAYMAP_SANITIZED_BUILD
  constexpr std::size_t kCutStep = 29;
  constexpr int kRounds = 120;
#else
  constexpr std::size_t kCutStep = 7;
  constexpr int kRounds = 400;
#endif
  std::mt19937 random(20261126);
  const std::string damaged = dir.file("damaged.mcap");
  for (const std::string& file : files) {
    const std::string original = bytesOf(file);
    // Every kCutStep-th truncation point, then random flips, overwrites and runs of 0xFF.
    for (std::size_t cut = 0; cut < original.size(); cut += kCutStep) {
      writeAll(damaged, original.substr(0, cut));
      readThrough(damaged);
    }
    for (int round = 0; round < kRounds; ++round) {
      std::string bytes = original;
      const int edits = 1 + static_cast<int>(random() % 4);
      for (int e = 0; e < edits; ++e) {
        const std::size_t at = random() % bytes.size();
        switch (random() % 3) {
          case 0:
            bytes[at] = static_cast<char>(bytes[at] ^ (1 << (random() % 8)));
            break;
          case 1:
            bytes[at] = static_cast<char>(random() % 256);
            break;
          default:
            for (std::size_t k = 0; k < 8 && at + k < bytes.size(); ++k) {
              bytes[at + k] = static_cast<char>(0xFF);  // huge lengths
            }
        }
      }
      writeAll(damaged, bytes);
      readThrough(damaged);
    }
  }
}

}  // namespace
}  // namespace raymap::test
