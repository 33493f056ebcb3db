// SPDX-License-Identifier: BSD-3-Clause
// Partial input is never success (issue 52): a damaged record in a complete MCAP file is damage,
// not a cut, and stops populate and replay naming the file and the offset, unless
// --skip-damaged asks for what can be read (then what was skipped is said); a file cut off is
// the same; a damaged end or summary is read by a linear scan with a warning.
#include <cstdint>
#include <filesystem>

#include <gtest/gtest.h>

#include "tests/rosbag/bag_fixture.hpp"
#include "tests/service/service_fixture.hpp"
#include "tests/support/file_bytes.hpp"

namespace raymap::test {
namespace {

/// The offsets of the top-level records of an MCAP file with opcode `op` (walked from the
/// magic through each record's length prefix up to the footer).
std::vector<std::size_t> mcapRecordsOf(const Bytes& bytes, std::uint8_t op) {
  std::vector<std::size_t> found;
  std::size_t at = 8;
  while (at + 9 <= bytes.size()) {
    const std::uint8_t code = bytes[at];
    const std::uint64_t length = getLe(bytes, at + 1, 8);
    if (code == op) {
      found.push_back(at);
    }
    if (code == 0x02) {
      break;  // the footer
    }
    at += 9 + static_cast<std::size_t>(length);
  }
  return found;
}

/// A drive of `scans` clouds as one indexed MCAP file whose chunks hold about one cloud each.
std::string chunkedDrive(const TempDir& dir, int scans) {
  const Drive drive = makeDrive(dir, DrivePoses::kOdometry, scans);
  const std::string file = dir.file("chunked.mcap");
  writeBag(drive.spec, file, {"--chunk-size", "60000", "--file-only"});
  return file;
}

TEST(BagIntegrity, ACorruptChunkLengthInACompleteFileIsDamageNotACutAndStopsPopulate) {
  REQUIRE_NODE_HARNESS();
  TempDir dir;
  const std::string file = chunkedDrive(dir, 6);
  const Bytes bytes = readFileBytes(file);
  const std::vector<std::size_t> chunks = mcapRecordsOf(bytes, 0x06);
  ASSERT_GE(chunks.size(), 4u);
  const std::size_t second = chunks[1];
  // One byte of the second chunk's length: far past the file, and a little longer (inside it).
  for (const auto& [byte, value] : {std::pair{6, 0x01}, std::pair{2, 0x7F}}) {
    Bytes damaged = bytes;
    damaged[second + 1 + static_cast<std::size_t>(byte)] = static_cast<std::uint8_t>(value);
    const std::string bad = dir.file("bad" + std::to_string(byte) + ".mcap");
    writeFileBytes(bad, damaged);
    const std::string map = dir.file("bad.rmap");
    const RunResult r = runRaymap({"populate", bad, "-o", map, "-q"});
    EXPECT_EQ(r.exit_code, 1) << describe(r);
    EXPECT_TRUE(contains(r.err, bad));
    EXPECT_TRUE(contains(r.err, "offset " + std::to_string(second)));
    EXPECT_TRUE(contains(r.err, "corrupt"));
    EXPECT_TRUE(contains(r.err, "--skip-damaged"));
    EXPECT_EQ(r.err.find("truncated"), std::string::npos) << r.err;
    EXPECT_FALSE(std::filesystem::exists(map));

    // Asked for: the rest is mapped from the next indexed chunk on, and the skip is named.
    const RunResult skip =
        runRaymap({"populate", bad, "--skip-damaged", "-o", map, "--stats-json", "-", "-q"});
    ASSERT_EQ(skip.exit_code, 0) << describe(skip);
    EXPECT_TRUE(contains(skip.err, "offset " + std::to_string(second)));
    EXPECT_TRUE(contains(skip.err, "skipped"));
    EXPECT_TRUE(contains(skip.err, "of the"));  // messages read of those the summary counts
    EXPECT_TRUE(std::filesystem::exists(map));
    const auto integrated = jsonValue(skip.out, "scans_integrated");
    ASSERT_TRUE(integrated.has_value()) << skip.out;
    EXPECT_GT(std::stoi(*integrated), 0);
    EXPECT_LT(std::stoi(*integrated), 6);
    std::filesystem::remove(map);
  }
}

TEST(BagIntegrity, ReplayOfACorruptChunkLengthFailsNamingTheOffsetUnlessAskedToSkip) {
  REQUIRE_NODE_HARNESS();
  TempDir dir;
  const std::string file = chunkedDrive(dir, 6);
  Bytes bytes = readFileBytes(file);
  const std::vector<std::size_t> chunks = mcapRecordsOf(bytes, 0x06);
  ASSERT_GE(chunks.size(), 4u);
  bytes[chunks[1] + 7] = 0x01;
  const std::string bad = dir.file("bad.mcap");
  writeFileBytes(bad, bytes);
  const std::string domain = std::to_string(uniqueDomain());
  const std::vector<std::string> replay = {"replay", bad,      "--domain", domain, "--wait",
                                           "0",      "--rate", "50",       "-q"};
  const RunResult r = runRaymap(replay);
  EXPECT_EQ(r.exit_code, 1) << describe(r);
  EXPECT_TRUE(contains(r.err, "offset " + std::to_string(chunks[1])));
  EXPECT_TRUE(contains(r.err, "corrupt"));
  EXPECT_EQ(r.err.find("truncated"), std::string::npos) << r.err;
  const RunResult skip = runRaymap(concat(replay, {"--skip-damaged"}));
  EXPECT_EQ(skip.exit_code, 0) << describe(skip);
  EXPECT_TRUE(contains(skip.err, "skipped"));
  EXPECT_TRUE(contains(skip.err, "offset " + std::to_string(chunks[1])));
}

TEST(BagIntegrity, ACutOffMcapFailsUnlessAskedAndThenSaysWhatIsMissing) {
  REQUIRE_NODE_HARNESS();
  TempDir dir;
  const std::string file = chunkedDrive(dir, 6);
  const Bytes bytes = readFileBytes(file);
  const std::string cut = dir.file("cut.mcap");
  writeFileBytes(cut, Bytes(bytes.begin(),
                            bytes.begin() + static_cast<std::ptrdiff_t>(bytes.size() * 6 / 10)));
  const std::string map = dir.file("cut.rmap");
  const RunResult r = runRaymap({"populate", cut, "-o", map, "-q"});
  EXPECT_EQ(r.exit_code, 1) << describe(r);
  EXPECT_TRUE(contains(r.err, cut));
  EXPECT_TRUE(contains(r.err, "truncated"));
  EXPECT_TRUE(contains(r.err, "offset "));
  EXPECT_FALSE(std::filesystem::exists(map));
  const RunResult skip = runRaymap({"populate", cut, "--skip-damaged", "-o", map, "-q"});
  EXPECT_EQ(skip.exit_code, 0) << describe(skip);
  EXPECT_TRUE(contains(skip.err, "truncated"));
  EXPECT_TRUE(contains(skip.err, "the rest is missing"));
  EXPECT_TRUE(std::filesystem::exists(map));
  // A description reads what there is and says that it is cut off.
  const RunResult info = runRaymap({"info", cut});
  EXPECT_EQ(info.exit_code, 0) << describe(info);
  EXPECT_TRUE(contains(info.err, "truncated"));
}

TEST(BagIntegrity, AMissingTailOrASummaryFailingItsCrcIsReadInOrderWithAWarning) {
  REQUIRE_NODE_HARNESS();
  TempDir dir;
  const std::string file = chunkedDrive(dir, 4);
  const Bytes bytes = readFileBytes(file);
  const RunResult whole = runRaymap({"populate", file, "--stats-json", "-", "-q"});
  ASSERT_EQ(whole.exit_code, 0) << describe(whole);
  // `head -c -4`: the end magic cut short; and one byte of the summary changed.
  Bytes summary_flipped = bytes;
  const std::vector<std::size_t> indexes = mcapRecordsOf(bytes, 0x08);  // chunk indexes
  ASSERT_FALSE(indexes.empty());
  summary_flipped[indexes.front() + 10] ^= 0x40;
  const std::vector<std::pair<Bytes, std::string>> cases = {
      {Bytes(bytes.begin(), bytes.end() - 4), "does not end with the MCAP magic"},
      {summary_flipped, "fails its CRC"}};
  for (const auto& [damaged, why] : cases) {
    const std::string bad = dir.file("tail.mcap");
    writeFileBytes(bad, damaged);
    const RunResult r = runRaymap({"populate", bad, "--stats-json", "-", "-q"});
    EXPECT_EQ(r.exit_code, 0) << describe(r);
    EXPECT_TRUE(contains(r.err, "warning: " + bad));
    EXPECT_TRUE(contains(r.err, why));
    EXPECT_TRUE(contains(r.err, "read in order"));
    // Nothing was lost: the same map as from the whole file.
    for (const char* key : {"rays_integrated", "voxels_occupied", "voxels_free"}) {
      EXPECT_EQ(jsonValue(r.out, key), jsonValue(whole.out, key)) << key;
    }
  }
}

}  // namespace
}  // namespace raymap::test
