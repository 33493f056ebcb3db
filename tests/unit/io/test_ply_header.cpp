// SPDX-License-Identifier: BSD-3-Clause
// PLY header parsing: formats, types, lists, and line-numbered errors.
#include <optional>
#include <ostream>
#include <string>

#include <gtest/gtest.h>

#include "src/io/byte_reader.hpp"
#include "src/io/ply_header.hpp"
#include "tests/support/ply_test_writer.hpp"
#include "tests/support/temp_dir.hpp"

namespace raymap::io {
namespace {

constexpr const char* kPath = "cloud.ply";

TEST(PlyHeader, ParsesFormatElementsAndProperties) {
  const std::string text =
      "ply\n"
      "format binary_big_endian 1.0\n"
      "comment made by hand\n"
      "obj_info scanner 7\n"
      "element vertex 12\n"
      "property float x\n"
      "property float64 Y\n"
      "property uchar alpha\n"
      "element face 3\n"
      "property list uint8 int32 vertex_indices\n"
      "end_header\n";

  const auto header = parsePlyHeader(text, kPath);

  ASSERT_TRUE(header.has_value()) << header.error().message;
  EXPECT_EQ(header->format, PlyFormat::kBinaryBigEndian);
  ASSERT_EQ(header->comments.size(), 1u);
  EXPECT_EQ(header->comments[0], "made by hand");
  ASSERT_EQ(header->obj_info.size(), 1u);
  EXPECT_EQ(header->obj_info[0], "scanner 7");
  ASSERT_EQ(header->elements.size(), 2u);
  const PlyElement& vertex = header->elements[0];
  EXPECT_EQ(vertex.name, "vertex");
  EXPECT_EQ(vertex.count, 12u);
  ASSERT_EQ(vertex.properties.size(), 3u);
  EXPECT_EQ(vertex.properties[1].type, PlyType::kFloat64);
  EXPECT_EQ(vertex.recordBytes(), 4u + 8u + 1u);
  EXPECT_FALSE(vertex.hasLists());
  EXPECT_EQ(vertex.findProperty("y"), std::optional<std::size_t>(1));  // case-insensitive
  EXPECT_EQ(vertex.findProperty("z"), std::nullopt);
  const PlyProperty& list = header->elements[1].properties[0];
  EXPECT_TRUE(list.is_list);
  EXPECT_EQ(list.count_type, PlyType::kUint8);
  EXPECT_EQ(list.type, PlyType::kInt32);
  EXPECT_TRUE(header->elements[1].hasLists());
  EXPECT_EQ(header->findElement("FACE"), std::optional<std::size_t>(1));
  EXPECT_EQ(header->header_lines, 11u);
  EXPECT_EQ(header->header_bytes, text.size());
}

TEST(PlyHeader, AcceptsEveryFormatAndCarriageReturns) {
  for (const char* format : {"ascii", "binary_little_endian", "binary_big_endian"}) {
    const std::string text = "ply\r\nformat " + std::string(format) +
                             " 1.0\r\nelement vertex 0\r\nproperty float x\r\nend_header\r\n";

    const auto header = parsePlyHeader(text, kPath);

    ASSERT_TRUE(header.has_value()) << header.error().message;
    EXPECT_STREQ(toString(header->format), format);
  }
}

TEST(PlyHeader, KnowsBothSpellingsOfEveryType) {
  const std::pair<const char*, const char*> spellings[] = {
      {"char", "int8"}, {"uchar", "uint8"}, {"short", "int16"},   {"ushort", "uint16"},
      {"int", "int32"}, {"uint", "uint32"}, {"float", "float32"}, {"double", "float64"}};
  const std::size_t sizes[] = {1, 1, 2, 2, 4, 4, 4, 8};
  for (std::size_t i = 0; i < std::size(spellings); ++i) {
    const auto classic = parsePlyType(spellings[i].first);
    const auto sized = parsePlyType(spellings[i].second);
    ASSERT_TRUE(classic.has_value()) << spellings[i].first;
    ASSERT_TRUE(sized.has_value()) << spellings[i].second;
    EXPECT_EQ(*classic, *sized);
    EXPECT_EQ(sizeOf(*classic), sizes[i]);
    EXPECT_STREQ(toString(*classic), spellings[i].first);
  }
  EXPECT_FALSE(parsePlyType("int64").has_value());
}

struct BadHeader {
  const char* name;
  std::string text;
  std::string message;  // expected in full, after the path

  friend void PrintTo(const BadHeader& bad, std::ostream* os) { *os << bad.name; }
};

class PlyHeaderErrors : public ::testing::TestWithParam<BadHeader> {};

TEST_P(PlyHeaderErrors, NameFileLineAndProblem) {
  const auto header = parsePlyHeader(GetParam().text, kPath);

  ASSERT_FALSE(header.has_value());
  EXPECT_EQ(header.error().code, ErrorCode::kFormat);
  EXPECT_EQ(header.error().message, std::string(kPath) + ": " + GetParam().message);
}

INSTANTIATE_TEST_SUITE_P(
    Cases, PlyHeaderErrors,
    ::testing::Values(
        BadHeader{"NoMagic", "plx\nformat ascii 1.0\nend_header\n",
                  "not a PLY file (missing 'ply' magic)"},
        BadHeader{"UnknownFormat", "ply\nformat binary_middle_endian 1.0\nend_header\n",
                  "line 2: unknown format 'binary_middle_endian'"},
        BadHeader{"Version", "ply\nformat ascii 2.0\nend_header\n",
                  "line 2: unsupported PLY version '2.0' (only 1.0)"},
        BadHeader{"NoEnd", "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n",
                  "header ends without 'end_header'"},
        BadHeader{"NoFormat", "ply\nelement vertex 1\nend_header\n",
                  "line 3: 'end_header' before any 'format' line"},
        BadHeader{"UnknownType", "ply\nformat ascii 1.0\nelement vertex 1\nproperty float128 x\n",
                  "line 4: unknown property type 'float128'"},
        BadHeader{"PropertyFirst", "ply\nformat ascii 1.0\nproperty float x\n",
                  "line 3: 'property' before any 'element'"},
        BadHeader{"BadCount", "ply\nformat ascii 1.0\nelement vertex many\n",
                  "line 3: invalid count 'many' for element 'vertex'"},
        BadHeader{"NegativeCount", "ply\nformat ascii 1.0\nelement vertex -4\n",
                  "line 3: invalid count '-4' for element 'vertex'"},
        BadHeader{"FloatListCount",
                  "ply\nformat ascii 1.0\nelement face 1\nproperty list float int idx\n",
                  "line 4: list count type 'float' is not an integer type"},
        BadHeader{"DuplicateProperty",
                  "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty double X\n",
                  "line 5: property 'X' declared twice in element 'vertex'"},
        BadHeader{"UnknownKeyword", "ply\nformat ascii 1.0\nelemnt vertex 1\n",
                  "line 3: unknown header keyword 'elemnt'"},
        BadHeader{"MissingName", "ply\nformat ascii 1.0\nelement vertex 1\nproperty float\n",
                  "line 4: expected 'property TYPE NAME'"}),
    [](const ::testing::TestParamInfo<BadHeader>& param_info) {
      return std::string(param_info.param.name);
    });

TEST(PlyHeader, ReadsFromGzipFileAndStopsAtFirstDataByte) {
  test::TempDir dir;
  const std::string header_text =
      "ply\nformat binary_little_endian 1.0\nelement vertex 1\nproperty uchar v\nend_header\n";
  const std::string path = dir.file("one.ply.gz");
  test::writeBytes(path, header_text + "\x2a", /*gzip=*/true);
  auto reader = ByteReader::open(path);
  ASSERT_TRUE(reader.has_value()) << reader.error().message;

  const auto header = parsePlyHeader(*reader);

  ASSERT_TRUE(header.has_value()) << header.error().message;
  EXPECT_TRUE(reader->compressed());
  EXPECT_EQ(header->header_bytes, header_text.size());
  ASSERT_EQ(reader->buffered().size(), 1u);
  EXPECT_EQ(reader->buffered()[0], std::byte{0x2a});
}

TEST(PlyHeader, AnEmptyFileSaysSo) {
  test::TempDir dir;
  const std::string path = dir.file("empty.ply");
  test::writeBytes(path, "");
  auto reader = ByteReader::open(path);
  ASSERT_TRUE(reader.has_value()) << reader.error().message;

  const auto from_file = parsePlyHeader(*reader);
  const auto from_text = parsePlyHeader("", kPath);

  ASSERT_FALSE(from_file.has_value());
  EXPECT_EQ(from_file.error().code, ErrorCode::kFormat);
  EXPECT_EQ(from_file.error().message, path + " is empty (0 bytes): not a PLY file");
  ASSERT_FALSE(from_text.has_value());
  EXPECT_EQ(from_text.error().message, std::string(kPath) + " is empty (0 bytes): not a PLY file");
}

TEST(PlyHeader, BinaryGarbageIsNotAPlyFile) {
  test::TempDir dir;
  const std::string path = dir.file("noise.bin");
  test::writeBytes(path, std::string(300, '\x01'));
  auto reader = ByteReader::open(path, 128);  // a "first line" longer than the buffer
  ASSERT_TRUE(reader.has_value()) << reader.error().message;

  const auto header = parsePlyHeader(*reader);

  ASSERT_FALSE(header.has_value());
  EXPECT_EQ(header.error().message, path + ": not a PLY file (missing 'ply' magic)");
}

// ---- many properties and elements (parsing stays linear; what is parsed is checked here) ----

constexpr int kMany = 100000;

/// A header with one vertex element of `count` float properties p0, p1, ..., then `extra` lines.
std::string manyProperties(int count, const std::string& extra = "") {
  std::string text = "ply\nformat binary_little_endian 1.0\nelement vertex 1\n";
  for (int i = 0; i < count; ++i) {
    text += "property float p" + std::to_string(i) + "\n";
  }
  return text + extra + "end_header\n";
}

TEST(PlyHeader, ParsesAHundredThousandPropertiesInOrder) {
  const auto header = parsePlyHeader(manyProperties(kMany), kPath);

  ASSERT_TRUE(header.has_value()) << header.error().message;
  ASSERT_EQ(header->elements.size(), 1u);
  const PlyElement& vertex = header->elements[0];
  ASSERT_EQ(vertex.properties.size(), static_cast<std::size_t>(kMany));
  EXPECT_EQ(vertex.properties.front().name, "p0");
  std::string last = std::to_string(kMany - 1);
  last.insert(0, 1, 'p');  // not "p" + ...: GCC 12 -O3 reports a false -Wrestrict on that
  EXPECT_EQ(vertex.properties.back().name, last);
  EXPECT_EQ(vertex.findProperty("P77777"), std::optional<std::size_t>(77777));
  EXPECT_EQ(vertex.recordBytes(), 4u * kMany);
}

TEST(PlyHeader, FindsADuplicateAmongAHundredThousandProperties) {
  // The duplicate differs in case only (names are compared case-insensitively).
  const auto header = parsePlyHeader(manyProperties(kMany, "property double P4242\n"), kPath);

  ASSERT_FALSE(header.has_value());
  EXPECT_EQ(header.error().message, std::string(kPath) + ": line " + std::to_string(kMany + 4) +
                                        ": property 'P4242' declared twice in element 'vertex'");
}

TEST(PlyHeader, FindsADuplicateAmongAHundredThousandElements) {
  std::string text = "ply\nformat ascii 1.0\n";
  for (int i = 0; i < kMany; ++i) {
    text += "element e" + std::to_string(i) + " 0\n";
  }
  text += "element E99998 0\nend_header\n";

  const auto header = parsePlyHeader(text, kPath);

  ASSERT_FALSE(header.has_value());
  EXPECT_EQ(header.error().message, std::string(kPath) + ": line " + std::to_string(kMany + 3) +
                                        ": element 'E99998' declared twice");
}

}  // namespace
}  // namespace raymap::io
