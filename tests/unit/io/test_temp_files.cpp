// SPDX-License-Identifier: BSD-3-Clause
// Temporary names ("<path>.raymap-tmp-<pid>"), the removal of those a dead process left, and
// AtomicFileWriter's use of them (one temporary per output, never a temporary of a temporary).
#include <climits>
#include <filesystem>
#include <fstream>
#include <set>
#include <string>

#include <gtest/gtest.h>
#include <unistd.h>

#include "src/io/atomic_file.hpp"
#include "src/io/temp_files.hpp"
#include "tests/support/file_bytes.hpp"
#include "tests/support/temp_dir.hpp"

namespace raymap::io {
namespace {

namespace fs = std::filesystem;
using test::TempDir;

std::set<std::string> namesIn(const fs::path& dir) {
  std::set<std::string> names;
  for (const auto& entry : fs::directory_iterator(dir)) {
    names.insert(entry.path().filename().string());
  }
  return names;
}

std::string contentOf(const std::string& path) {
  const test::Bytes bytes = test::readFileBytes(path);
  return std::string(bytes.begin(), bytes.end());
}

void writeText(const std::string& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
  ASSERT_TRUE(out.good()) << path;
}

const std::string kOwnSuffix = ".raymap-tmp-" + std::to_string(::getpid());

TEST(TemporaryNames, AreThePathThePatternAndThisProcess) {
  EXPECT_EQ(temporaryPathFor("dir/map.rmap"), "dir/map.rmap" + kOwnSuffix);
  EXPECT_TRUE(isOwnTemporaryPath("dir/map.rmap" + kOwnSuffix));
  EXPECT_FALSE(isOwnTemporaryPath("dir/map.rmap"));
  EXPECT_FALSE(isOwnTemporaryPath("dir/map.rmap.raymap-tmp-" + std::to_string(INT_MAX)));
  EXPECT_FALSE(isOwnTemporaryPath("dir/map.rmap.raymap-tmp-"));
  EXPECT_FALSE(isOwnTemporaryPath(kOwnSuffix));  // a name that is only the suffix
  EXPECT_FALSE(isOwnTemporaryPath("dir/map.rmap" + kOwnSuffix + "x"));
}

TEST(AtomicFileWriter, WritesUnderTheTemporaryNameUntilCommit) {
  // Arrange
  TempDir dir;
  const std::string path = dir.file("out.txt");
  auto writer = AtomicFileWriter::open(path);
  ASSERT_TRUE(writer.has_value()) << writer.error().message;
  ASSERT_TRUE(writer->write(std::string("data")).has_value());

  // Act
  const std::set<std::string> while_writing = namesIn(dir.path());
  ASSERT_TRUE(writer->commit().has_value());

  // Assert
  EXPECT_EQ(while_writing, std::set<std::string>{"out.txt" + kOwnSuffix});
  EXPECT_EQ(namesIn(dir.path()), std::set<std::string>{"out.txt"});
  EXPECT_EQ(contentOf(path), "data");
}

TEST(AtomicFileWriter, WritesAStagedTemporaryInPlaceAndLeavesTheRenameToItsOwner) {
  // Arrange: the owner of a group of outputs made the temporary name.
  TempDir dir;
  const std::string staged = temporaryPathFor(dir.file("out.txt"));
  writeText(staged, "");

  // Act
  auto writer = AtomicFileWriter::open(staged);
  ASSERT_TRUE(writer.has_value()) << writer.error().message;
  ASSERT_TRUE(writer->write(std::string("data")).has_value());
  ASSERT_TRUE(writer->commit().has_value());

  // Assert: no temporary of the temporary, and no destination yet.
  EXPECT_EQ(writer->path(), dir.file("out.txt"));  // messages name the output
  EXPECT_EQ(namesIn(dir.path()), std::set<std::string>{"out.txt" + kOwnSuffix});
  EXPECT_EQ(contentOf(staged), "data");
}

TEST(AtomicFileWriter, DoesNotWriteThroughALinkPlantedUnderItsTemporaryName) {
  // Arrange
  TempDir dir;
  const std::string victim = dir.file("victim.txt");
  writeText(victim, "precious");
  const std::string path = dir.file("out.txt");
  fs::create_symlink(victim, temporaryPathFor(path));

  // Act
  auto writer = AtomicFileWriter::open(path);
  ASSERT_TRUE(writer.has_value()) << writer.error().message;
  ASSERT_TRUE(writer->write(std::string("data")).has_value());
  ASSERT_TRUE(writer->commit().has_value());

  // Assert
  EXPECT_EQ(contentOf(victim), "precious");
  EXPECT_EQ(contentOf(path), "data");
  EXPECT_FALSE(fs::is_symlink(path));
}

TEST(StaleTemporaries, OnlyThoseOfTheOutputWithADeadProcessAreRemoved) {
  // Arrange
  TempDir dir;
  const std::string output = dir.file("map.rmap");
  const std::string dead = output + ".raymap-tmp-" + std::to_string(INT_MAX - 1);
  const std::set<std::string> kept = {
      "map.rmap",
      "map.rmap" + kOwnSuffix,                                     // this process
      "map.rmap.raymap-tmp-1",                                     // init: alive
      "other.rmap.raymap-tmp-" + std::to_string(INT_MAX - 1),      // another output
      "map.rmap.raymap-tmp-" + std::to_string(INT_MAX - 1) + "x",  // not a pid
      "map.rmap.raymap-tmp--5",                                    // not a pid
      "map.rmap.raymap-tmp-99999999999999999999",                  // beyond pid_t
      "map.rmap.tmp-" + std::to_string(INT_MAX - 1),               // not the pattern
  };
  writeText(dead, "stale");
  for (const std::string& name : kept) {
    writeText(dir.file(name), "keep");
  }
  fs::create_symlink("map.rmap", output + ".raymap-tmp-" + std::to_string(INT_MAX - 2));

  // Act
  const StaleTemporaries result = removeStaleTemporaries(output);

  // Assert
  EXPECT_EQ(result.removed, std::vector<std::string>{dead});
  EXPECT_TRUE(result.errors.empty());
  std::set<std::string> expected = kept;
  expected.insert("map.rmap.raymap-tmp-" + std::to_string(INT_MAX - 2));  // a link: not ours
  EXPECT_EQ(namesIn(dir.path()), expected);
}

TEST(StaleTemporaries, AMissingDirectoryHasNone) {
  const StaleTemporaries result = removeStaleTemporaries("/nonexistent-raymap-dir/map.rmap");
  EXPECT_TRUE(result.removed.empty());
  EXPECT_TRUE(result.errors.empty());
}

}  // namespace
}  // namespace raymap::io
