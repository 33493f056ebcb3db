// SPDX-License-Identifier: BSD-3-Clause
// io::StagedOutputs: a program's outputs appear together on commit() or not at all, an output
// that is an input (or another output) is refused before any work, and an existing file is left
// as it was until the commit replaces it.
#include <filesystem>
#include <fstream>
#include <string>

#include <gtest/gtest.h>

#include "src/io/staged_outputs.hpp"
#include "tests/support/file_bytes.hpp"
#include "tests/support/temp_dir.hpp"

namespace raymap::io {
namespace {

namespace fs = std::filesystem;
using test::TempDir;

void writeOutput(const std::string& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
  ASSERT_TRUE(out.good()) << path;
}

std::string outputText(const std::string& path) {
  const test::Bytes bytes = test::readFileBytes(path);
  return std::string(bytes.begin(), bytes.end());
}

TEST(StagedOutputs, NothingAppearsUntilCommitThenEveryOutputDoes) {
  // Arrange
  TempDir dir;
  const std::string map = dir.file("map.rmap");
  const std::string png = dir.file("map.png");
  StagedOutputs staged("test");
  const Result<std::string> map_temp = staged.add(map, "--output");
  const Result<std::string> png_temp = staged.add(png, "--png");
  ASSERT_TRUE(map_temp.has_value()) << map_temp.error().message;
  ASSERT_TRUE(png_temp.has_value()) << png_temp.error().message;

  // Act
  writeOutput(*map_temp, "map");
  writeOutput(*png_temp, "png");
  const bool before_commit = fs::exists(map) || fs::exists(png);
  const Expected<void, Error> committed = staged.commit();

  // Assert
  EXPECT_FALSE(before_commit);
  ASSERT_TRUE(committed.has_value()) << committed.error().message;
  EXPECT_EQ(outputText(map), "map");
  EXPECT_EQ(outputText(png), "png");
  EXPECT_FALSE(fs::exists(*map_temp));
  EXPECT_FALSE(fs::exists(*png_temp));
}

TEST(StagedOutputs, WithoutACommitTheTemporariesGoAndAnOldOutputStays) {
  // Arrange
  TempDir dir;
  const std::string old_output = dir.file("old.csv");
  writeOutput(old_output, "previous run");
  std::string temp;

  // Act: a run that fails after staging its output.
  {
    StagedOutputs staged("test");
    const Result<std::string> staged_path = staged.add(old_output, "--csv");
    ASSERT_TRUE(staged_path.has_value()) << staged_path.error().message;
    temp = *staged_path;
    writeOutput(temp, "half a new file");
  }

  // Assert
  EXPECT_FALSE(fs::exists(temp));
  EXPECT_EQ(outputText(old_output), "previous run");
}

TEST(StagedOutputs, AnOutputThatIsAnInputOrAnotherOutputIsAUsageError) {
  // Arrange
  TempDir dir;
  const std::string input = dir.file("rays.ply");
  writeOutput(input, "ply");
  fs::create_directories(dir.file("sub"));
  StagedOutputs staged("test");
  staged.input(input, "input");

  // Act
  const Result<std::string> same_as_input = staged.add(dir.file("sub/../rays.ply"), "--output");
  const Result<std::string> first = staged.add(dir.file("a.png"), "--png");
  const Result<std::string> twice = staged.add(dir.file("sub/../a.png"), "--csv");

  // Assert
  ASSERT_FALSE(same_as_input.has_value());
  EXPECT_EQ(same_as_input.error().code, ErrorCode::kInvalidArgument);
  EXPECT_NE(same_as_input.error().message.find("--output"), std::string::npos);
  EXPECT_NE(same_as_input.error().message.find("same file as input"), std::string::npos);
  EXPECT_EQ(outputText(input), "ply");
  ASSERT_TRUE(first.has_value()) << first.error().message;
  ASSERT_FALSE(twice.has_value());
  EXPECT_EQ(twice.error().code, ErrorCode::kInvalidArgument);
  EXPECT_NE(twice.error().message.find("--png"), std::string::npos);
}

TEST(StagedOutputs, AnUnwritableOutputFailsAtAddNamingTheOption) {
  // Arrange
  TempDir dir;
  fs::create_directories(dir.file("folder"));
  StagedOutputs staged("test");

  // Act
  const Result<std::string> a_directory = staged.add(dir.file("folder"), "--png");
  const Result<std::string> no_parent = staged.add(dir.file("missing/out.csv"), "--csv");

  // Assert
  ASSERT_FALSE(a_directory.has_value());
  EXPECT_EQ(a_directory.error().code, ErrorCode::kIo);
  EXPECT_NE(a_directory.error().message.find("--png"), std::string::npos);
  ASSERT_FALSE(no_parent.has_value());
  EXPECT_EQ(no_parent.error().code, ErrorCode::kIo);
  EXPECT_NE(no_parent.error().message.find("--csv"), std::string::npos);
  EXPECT_FALSE(fs::exists(dir.file("missing")));
}

}  // namespace
}  // namespace raymap::io
