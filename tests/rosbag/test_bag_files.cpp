// SPDX-License-Identifier: BSD-3-Clause
// Bags as rosbag2 leaves them on disk (issue 52): a directory whose metadata.yaml is missing
// (what `ros2 bag reindex` repairs) is read from its files; a file compressed as a whole with
// zstd (rosbag2's compression_mode: file) is named as such, with the command that decompresses it.
#include <filesystem>

#include <gtest/gtest.h>
#include <zstd.h>

#include "tests/rosbag/bag_fixture.hpp"
#include "tests/service/service_fixture.hpp"
#include "tests/support/file_bytes.hpp"

namespace raymap::test {
namespace {

TEST(BagFiles, ADirectoryWithoutMetadataIsReadFromItsMcapFiles) {
  REQUIRE_NODE_HARNESS();
  TempDir dir;
  const Drive drive = makeDrive(dir, DrivePoses::kOdometry, 4);
  const std::string bag = dir.file("drive_bag");
  writeBag(drive.spec, bag, {});
  const RunResult whole = runRaymap({"populate", bag, "--stats-json", "-", "-q"});
  ASSERT_EQ(whole.exit_code, 0) << describe(whole);
  ASSERT_TRUE(std::filesystem::remove(bag + "/metadata.yaml"));
  const RunResult r = runRaymap({"populate", bag, "--stats-json", "-", "-q"});
  EXPECT_EQ(r.exit_code, 0) << describe(r);
  for (const char* key :
       {"rays_integrated", "voxels_occupied", "voxels_free", "scans_integrated"}) {
    EXPECT_EQ(jsonValue(r.out, key), jsonValue(whole.out, key)) << key;
  }
  // A directory with neither is refused, named.
  const std::string empty = dir.file("not_a_bag");
  std::filesystem::create_directory(empty);
  writeText(empty + "/notes.txt", "nothing here\n");
  const RunResult none = runRaymap({"populate", empty, "-o", dir.file("m.rmap"), "-q"});
  EXPECT_EQ(none.exit_code, 1) << describe(none);
  EXPECT_TRUE(contains(none.err, empty));
}

TEST(BagFiles, AWholeFileZstdBagSaysHowToDecompressIt) {
  REQUIRE_NODE_HARNESS();
  TempDir dir;
  const Drive drive = makeDrive(dir, DrivePoses::kOdometry, 2);
  const std::string mcap = dir.file("drive.mcap");
  writeBag(drive.spec, mcap, {"--file-only"});
  const Bytes plain = readFileBytes(mcap);
  Bytes packed(ZSTD_compressBound(plain.size()));
  const std::size_t n = ZSTD_compress(packed.data(), packed.size(), plain.data(), plain.size(), 1);
  ASSERT_EQ(ZSTD_isError(n), 0u);
  packed.resize(n);
  const std::string zstd = dir.file("drive.mcap.zstd");
  writeFileBytes(zstd, packed);
  const std::string map = dir.file("m.rmap");
  const RunResult r = runRaymap({"populate", zstd, "-o", map, "-q"});
  EXPECT_EQ(r.exit_code, 1) << describe(r);
  EXPECT_TRUE(contains(r.err, zstd + ": compressed as a whole with zstd"));
  EXPECT_TRUE(contains(r.err, "zstd -d " + zstd));
  EXPECT_EQ(r.err.find("PLY"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(map));
  const RunResult replay =
      runRaymap({"replay", zstd, "--domain", std::to_string(uniqueDomain()), "--wait", "0", "-q"});
  EXPECT_EQ(replay.exit_code, 1) << describe(replay);
  EXPECT_TRUE(contains(replay.err, "zstd -d " + zstd));
}

}  // namespace
}  // namespace raymap::test
