// SPDX-License-Identifier: BSD-3-Clause
// ByteReader and PlyVertexReader: encodings, types, skipping, chunking, and damaged files.
#include <cstdint>
#include <cstdio>
#include <limits>
#include <ostream>
#include <string>
#include <tuple>
#include <vector>

#include <gtest/gtest.h>

#include "src/io/byte_reader.hpp"
#include "src/io/ply_reader.hpp"
#include "tests/support/ply_test_writer.hpp"
#include "tests/support/temp_dir.hpp"

namespace raymap::io {
namespace {

using test::PlyEncoding;
using test::PlyTestElement;
using test::PlyTestFile;

::testing::AssertionResult contains(const std::string& text, const std::string& part) {
  if (text.find(part) != std::string::npos) {
    return ::testing::AssertionSuccess();
  }
  return ::testing::AssertionFailure() << "'" << text << "' does not contain '" << part << "'";
}

std::string fileAsString(const std::string& path) {
  std::string bytes;
  std::FILE* in = std::fopen(path.c_str(), "rb");
  if (in == nullptr) {
    return bytes;
  }
  char block[4096];
  std::size_t n = 0;
  while ((n = std::fread(block, 1, sizeof(block), in)) > 0) {
    bytes.append(block, n);
  }
  std::fclose(in);
  return bytes;
}

/// Three float coordinates per vertex: vertex i is (i, 2i, -i / 4).
PlyTestElement xyzVertices(std::uint64_t count) {
  PlyTestElement vertex{"vertex", {{"float", "x", ""}, {"float", "y", ""}, {"float", "z", ""}}};
  for (std::uint64_t i = 0; i < count; ++i) {
    const double v = static_cast<double>(i);
    vertex.add({v, 2.0 * v, -v / 4.0});
  }
  return vertex;
}

/// Opens `path`, selects the named properties and reads every vertex `chunk` rows at a time.
Result<std::vector<double>> readColumns(
    const std::string& path, const std::vector<std::string>& names, std::size_t chunk,
    std::size_t buffer_bytes = ByteReader::kDefaultBufferBytes) {
  auto ply = PlyVertexReader::open(path, buffer_bytes);
  if (!ply) {
    return Unexpected(std::move(ply).error());
  }
  std::vector<std::size_t> indices;
  for (const std::string& name : names) {
    const auto index = ply->vertex().findProperty(name);
    if (!index) {
      return fail(ErrorCode::kFormat, "test: no property " + name);
    }
    indices.push_back(*index);
  }
  if (auto selected = ply->selectColumns(indices); !selected) {
    return Unexpected(std::move(selected).error());
  }
  std::vector<double> all;
  std::vector<double> rows(chunk * names.size());
  for (;;) {
    auto got = ply->read(rows);
    if (!got) {
      return Unexpected(std::move(got).error());
    }
    if (*got == 0) {
      break;
    }
    all.insert(all.end(), rows.begin(),
               rows.begin() + static_cast<std::ptrdiff_t>(*got * names.size()));
  }
  return all;
}

// ---- ByteReader ----

TEST(ByteReader, ReadsLinesWithAnyEndingFromPlainAndGzipFiles) {
  test::TempDir dir;
  for (const bool gzip : {false, true}) {
    const std::string path = dir.file(gzip ? "lines.txt.gz" : "lines.txt");
    test::writeBytes(path, "first\r\nsecond\n\nlast", gzip);
    auto reader = ByteReader::open(path);
    ASSERT_TRUE(reader.has_value()) << reader.error().message;

    std::vector<std::string> lines;
    std::string_view line;
    for (;;) {
      auto got = reader->readLine(line);
      ASSERT_TRUE(got.has_value()) << got.error().message;
      if (!*got) {
        break;
      }
      lines.emplace_back(line);
    }

    EXPECT_EQ(reader->compressed(), gzip);
    EXPECT_EQ(lines, (std::vector<std::string>{"first", "second", "", "last"}));
    EXPECT_EQ(reader->lineNumber(), 4u);
    EXPECT_DOUBLE_EQ(reader->progress(), 1.0);
  }
}

TEST(ByteReader, ExactReadsReportTruncation) {
  test::TempDir dir;
  const std::string path = dir.file("ten.bin");
  test::writeBytes(path, "0123456789");
  auto reader = ByteReader::open(path, 64);
  ASSERT_TRUE(reader.has_value()) << reader.error().message;
  std::byte four[4];
  std::byte eight[8];

  const auto first = reader->readExact(four, "a header");
  const auto second = reader->readExact(eight, "a record");

  ASSERT_TRUE(first.has_value()) << first.error().message;
  EXPECT_EQ(four[3], std::byte{'3'});
  ASSERT_FALSE(second.has_value());
  EXPECT_EQ(second.error().code, ErrorCode::kTruncated);
  EXPECT_EQ(second.error().message,
            path + ": truncated: a record needs 8 bytes at byte 4, the data ends after 6");
}

TEST(ByteReader, SkipsAndEnsuresAcrossRefills) {
  test::TempDir dir;
  const std::string path = dir.file("count.bin.gz");
  std::string bytes;
  for (int i = 0; i < 1000; ++i) {
    bytes += static_cast<char>(i % 251);
  }
  test::writeBytes(path, bytes, /*gzip=*/true);
  auto reader = ByteReader::open(path, 64);
  ASSERT_TRUE(reader.has_value()) << reader.error().message;

  const auto skipped = reader->skip(500);
  const auto window = reader->ensure(100);  // larger than the buffer: it grows

  ASSERT_TRUE(skipped.has_value());
  EXPECT_EQ(*skipped, 500u);
  ASSERT_TRUE(window.has_value()) << window.error().message;
  ASSERT_GE(window->size(), 100u);
  EXPECT_EQ((*window)[0], static_cast<std::byte>(500 % 251));
  EXPECT_EQ((*window)[99], static_cast<std::byte>(599 % 251));
  reader->consume(100);
  const auto rest = reader->skip(std::numeric_limits<std::uint64_t>::max());
  ASSERT_TRUE(rest.has_value());
  EXPECT_EQ(*rest, 400u);
  EXPECT_EQ(reader->position(), 1000u);
}

/// The bytes of `text` gzip-compressed (one gzip member), through a file in `dir`.
std::string gzipped(const test::TempDir& dir, const std::string& text) {
  const std::string path = dir.file("member.gz");
  test::writeBytes(path, text, /*gzip=*/true);
  return fileAsString(path);
}

/// Everything a reader decodes, or its error.
Result<std::string> readEverything(const std::string& path, std::size_t buffer_bytes) {
  auto reader = ByteReader::open(path, buffer_bytes);
  if (!reader) {
    return Unexpected(reader.error());
  }
  std::string text;
  std::byte chunk[100];
  for (;;) {
    auto got = reader->read(chunk);
    if (!got) {
      return Unexpected(got.error());
    }
    if (*got == 0) {
      return text;
    }
    text.append(reinterpret_cast<const char*>(chunk), *got);
  }
}

TEST(ByteReader, ConcatenatedGzipMembersAreOneStream) {
  // gzip allows members back to back (`cat a.gz b.gz`); all of them are the data. A small buffer
  // puts member boundaries inside and between reads.
  test::TempDir dir;
  std::string first;
  for (int i = 0; i < 3000; ++i) {
    first += static_cast<char>('a' + i % 26);
  }
  const std::string path = dir.file("two.gz");
  test::writeBytes(path, gzipped(dir, first) + gzipped(dir, "") + gzipped(dir, "second\n"));

  for (const std::size_t buffer : {std::size_t{64}, ByteReader::kDefaultBufferBytes}) {
    SCOPED_TRACE(buffer);
    const auto text = readEverything(path, buffer);

    ASSERT_TRUE(text.has_value()) << text.error().message;
    EXPECT_EQ(*text, first + "second\n");
  }
}

TEST(ByteReader, DataAfterTheGzipStreamIsAnErrorNamingItsOffset) {
  test::TempDir dir;
  const std::string member = gzipped(dir, "the data\n");
  for (const std::string& trailer : {std::string("garbage!"), std::string(512, '\0'),
                                     std::string("\x1f"), std::string(1, '\x8b')}) {
    SCOPED_TRACE(trailer.size());
    const std::string path = dir.file("trailing.gz");
    test::writeBytes(path, member + trailer);

    const auto text = readEverything(path, 64);

    ASSERT_FALSE(text.has_value());
    EXPECT_EQ(text.error().code, ErrorCode::kCorrupt);
    EXPECT_EQ(text.error().message,
              path + ": " + std::to_string(trailer.size()) +
                  " bytes of unexpected data after the gzip stream, at byte " +
                  std::to_string(member.size()) + " (not another gzip member)");
  }
}

TEST(ByteReader, CorruptSecondGzipMemberIsCorrupt) {
  test::TempDir dir;
  std::string second = gzipped(dir, "second member\n");
  second[12] = static_cast<char>(second[12] ^ 0x55);  // inside the deflate data
  const std::string path = dir.file("bad-second.gz");
  test::writeBytes(path, gzipped(dir, "first\n") + second);

  const auto text = readEverything(path, 64);

  ASSERT_FALSE(text.has_value());
  EXPECT_TRUE(contains(text.error().message, path + ": ")) << text.error().message;
  EXPECT_EQ(text.error().code, ErrorCode::kCorrupt);
}

TEST(ByteReader, MissingFileNamesPathAndReason) {
  test::TempDir dir;
  const std::string path = dir.file("absent.ply");

  const auto reader = ByteReader::open(path);

  ASSERT_FALSE(reader.has_value());
  EXPECT_EQ(reader.error().code, ErrorCode::kIo);
  EXPECT_TRUE(contains(reader.error().message, path + ": cannot open: "));
}

TEST(ByteReader, CutGzipStreamIsTruncated) {
  test::TempDir dir;
  const std::string whole = dir.file("whole.gz");
  std::string bytes;
  for (int i = 0; i < 200000; ++i) {
    bytes += static_cast<char>((i * 7919) % 256);
  }
  test::writeBytes(whole, bytes, /*gzip=*/true);
  const std::string compressed = fileAsString(whole);
  const std::string cut = dir.file("cut.gz");
  test::writeBytes(cut, compressed.substr(0, compressed.size() / 2));
  auto reader = ByteReader::open(cut, 4096);

  Result<std::uint64_t> skipped = std::uint64_t{0};
  if (reader) {
    skipped = reader->skip(std::numeric_limits<std::uint64_t>::max());
  }

  const Error& error = reader ? skipped.error() : reader.error();
  EXPECT_EQ(error.code, ErrorCode::kTruncated);
  EXPECT_TRUE(contains(error.message, cut + ": truncated"));
}

// ---- PlyVertexReader: encodings, types, order, skipping ----

class PlyEveryEncoding : public ::testing::TestWithParam<std::tuple<PlyEncoding, bool>> {};

TEST_P(PlyEveryEncoding, ReadsAnyTypesInAnyOrderAndSkipsOtherElements) {
  const auto [encoding, gzip] = GetParam();
  test::TempDir dir;
  PlyTestFile file;
  file.encoding = encoding;
  file.gzip = gzip;
  file.comments = {"mixed types, lists before and after the vertices"};
  PlyTestElement camera{"camera", {{"float", "fov", ""}, {"int", "ids", "uchar"}}};
  camera.add({1.5, 3, 7, 8, 9});
  camera.add({2.5, 0});
  PlyTestElement vertex{"vertex",
                        {{"uchar", "alpha", ""},
                         {"double", "Z", ""},
                         {"float32", "x", ""},
                         {"int8", "s8", ""},
                         {"ushort", "u16", ""},
                         {"int32", "i32", ""},
                         {"uint", "u32", ""},
                         {"float64", "y", ""}}};
  vertex.add({255, 0.1, 1.5, -128, 65535, -2147483648.0, 4294967295.0, -1e-7});
  vertex.add({0, -3.25, -2.25, 127, 0, 2147483647, 0, 1e300});
  vertex.add({17, 12345.678, 1e3, -1, 300, -5, 7, 0});
  PlyTestElement face{"face", {{"uint", "vertex_indices", "uchar"}}};
  face.add({3, 0, 1, 2});
  file.elements = {camera, vertex, face};
  const std::string path = dir.file(gzip ? "mixed.ply.gz" : "mixed.ply");
  test::writePly(path, file);

  const auto values = readColumns(path, {"x", "y", "z", "alpha", "s8", "u16", "i32", "u32"}, 2);

  ASSERT_TRUE(values.has_value()) << values.error().message;
  const std::vector<double> expected{1.5,
                                     -1e-7,
                                     0.1,
                                     255,
                                     -128,
                                     65535,
                                     -2147483648.0,
                                     4294967295.0,  //
                                     -2.25,
                                     1e300,
                                     -3.25,
                                     0,
                                     127,
                                     0,
                                     2147483647,
                                     0,  //
                                     1e3,
                                     0,
                                     12345.678,
                                     17,
                                     -1,
                                     300,
                                     -5,
                                     7};
  EXPECT_EQ(*values, expected);
}

INSTANTIATE_TEST_SUITE_P(
    Encodings, PlyEveryEncoding,
    ::testing::Combine(::testing::Values(PlyEncoding::kAscii, PlyEncoding::kBinaryLittleEndian,
                                         PlyEncoding::kBinaryBigEndian),
                       ::testing::Bool()),
    [](const ::testing::TestParamInfo<std::tuple<PlyEncoding, bool>>& param_info) {
      return std::string(test::toString(std::get<0>(param_info.param))) +
             (std::get<1>(param_info.param) ? "_gz" : "");
    });

TEST(PlyVertexReader, BinaryVerticesWithListPropertiesAreDecoded) {
  for (const PlyEncoding encoding :
       {PlyEncoding::kBinaryLittleEndian, PlyEncoding::kBinaryBigEndian, PlyEncoding::kAscii}) {
    test::TempDir dir;
    PlyTestFile file;
    file.encoding = encoding;
    PlyTestElement vertex{"vertex",
                          {{"float", "x", ""}, {"short", "ids", "uint"}, {"double", "y", ""}}};
    vertex.add({1, 2, 10, 11, -4});
    vertex.add({2, 0, -8});
    vertex.add({3, 3, 1, 2, 3, -12});
    file.elements = {vertex};
    const std::string path = dir.file("lists.ply");
    test::writePly(path, file);

    const auto values = readColumns(path, {"y", "x"}, 2);

    ASSERT_TRUE(values.has_value()) << values.error().message;
    EXPECT_EQ(*values, (std::vector<double>{-4, 1, -8, 2, -12, 3})) << test::toString(encoding);
  }
}

TEST(PlyVertexReader, RecordsStraddlingBufferRefillsDecodeExactly) {
  for (const PlyEncoding encoding :
       {PlyEncoding::kBinaryLittleEndian, PlyEncoding::kBinaryBigEndian, PlyEncoding::kAscii}) {
    test::TempDir dir;
    PlyTestFile file;
    file.encoding = encoding;
    file.gzip = encoding == PlyEncoding::kBinaryBigEndian;
    // 13-byte records against a 64-byte buffer: almost every record crosses a refill.
    PlyTestElement vertex{
        "vertex",
        {{"float", "x", ""}, {"float", "y", ""}, {"uchar", "scan", ""}, {"float", "z", ""}}};
    std::vector<double> expected;
    for (int i = 0; i < 1000; ++i) {
      const double x = i * 0.5;
      const double scan = i % 256;
      vertex.add({x, -x, scan, x + 0.25});
      expected.insert(expected.end(), {x + 0.25, scan, -x, x});
    }
    file.elements = {vertex};
    const std::string path = dir.file("boundaries.ply");
    test::writePly(path, file);

    const auto values = readColumns(path, {"z", "scan", "y", "x"}, 37, 64);

    ASSERT_TRUE(values.has_value()) << values.error().message;
    EXPECT_EQ(*values, expected) << test::toString(encoding);
  }
}

// ---- damaged files ----

class PlyDamage : public ::testing::TestWithParam<PlyEncoding> {};

TEST_P(PlyDamage, TruncatedDataNamesDeclaredCountAndLastVertex) {
  test::TempDir dir;
  PlyTestFile file;
  file.encoding = GetParam();
  file.elements = {xyzVertices(10)};
  if (GetParam() == PlyEncoding::kAscii) {
    file.elements[0] = xyzVertices(3);
    file.elements[0].declared_count = 10;
  } else {
    file.truncate_data_to = 3 * 12 + 5;  // three whole vertices and part of the fourth
  }
  const std::string path = dir.file("cut.ply");
  test::writePly(path, file);

  const auto values = readColumns(path, {"x", "y", "z"}, 4);

  ASSERT_FALSE(values.has_value());
  EXPECT_EQ(values.error().code, ErrorCode::kTruncated);
  EXPECT_EQ(values.error().message,
            path + ": truncated: header declares 10 vertices, data ends in vertex 4");
}

TEST_P(PlyDamage, DeclaringTooFewVerticesLeavesUnexpectedTrailingData) {
  test::TempDir dir;
  PlyTestFile file;
  file.encoding = GetParam();
  file.elements = {xyzVertices(5)};
  file.elements[0].declared_count = 3;
  const std::string path = dir.file("extra.ply");
  test::writePly(path, file);

  const auto values = readColumns(path, {"x", "y", "z"}, 100);

  ASSERT_FALSE(values.has_value());
  EXPECT_EQ(values.error().code, ErrorCode::kFormat);
  if (GetParam() == PlyEncoding::kAscii) {
    // Header: ply, format, element, 3 properties, end_header = 7 lines; vertex 4 is on line 11.
    EXPECT_EQ(values.error().message,
              path +
                  ": line 11: unexpected data after the last vertex (2 more non-empty lines; "
                  "the header declares 3 vertices)");
  } else {
    EXPECT_EQ(values.error().message,
              path +
                  ": 24 bytes of unexpected data after the last vertex (the header declares 3 "
                  "vertices)");
  }
}

TEST_P(PlyDamage, TruncatedElementBeforeVertexIsNamed) {
  test::TempDir dir;
  PlyTestFile file;
  file.encoding = GetParam();
  PlyTestElement camera{"camera", {{"int", "ids", "uchar"}}};
  camera.add({2, 5, 6});
  camera.declared_count = 4;
  file.elements = {camera, xyzVertices(0)};
  const std::string path = dir.file("camera.ply");
  test::writePly(path, file);

  const auto ply = PlyVertexReader::open(path);

  ASSERT_FALSE(ply.has_value());
  EXPECT_EQ(ply.error().message,
            path +
                ": truncated: header declares 4 'camera' elements, data ends in 'camera' "
                "element 2");
}

TEST_P(PlyDamage, DataAfterALaterElementIsNotChecked) {
  test::TempDir dir;
  PlyTestFile file;
  file.encoding = GetParam();
  PlyTestElement face{"face", {{"int", "vertex_indices", "uchar"}}};
  face.add({3, 0, 1, 2});
  file.elements = {xyzVertices(4), face};
  file.trailing = "whatever follows the faces is not read\n";
  const std::string path = dir.file("later.ply");
  test::writePly(path, file);

  const auto values = readColumns(path, {"x"}, 3);

  ASSERT_TRUE(values.has_value()) << values.error().message;
  EXPECT_EQ(*values, (std::vector<double>{0, 1, 2, 3}));
}

INSTANTIATE_TEST_SUITE_P(Encodings, PlyDamage,
                         ::testing::Values(PlyEncoding::kAscii, PlyEncoding::kBinaryLittleEndian,
                                           PlyEncoding::kBinaryBigEndian),
                         [](const ::testing::TestParamInfo<PlyEncoding>& param_info) {
                           return std::string(test::toString(param_info.param));
                         });

TEST(PlyVertexReader, TrailingBytesAfterLastBinaryVertexAreCounted) {
  test::TempDir dir;
  PlyTestFile file;
  file.gzip = true;
  file.elements = {xyzVertices(2)};
  file.trailing = "garbage";
  const std::string path = dir.file("garbage.ply.gz");
  test::writePly(path, file);

  const auto values = readColumns(path, {"x", "y", "z"}, 8);

  ASSERT_FALSE(values.has_value());
  EXPECT_EQ(values.error().message,
            path +
                ": 7 bytes of unexpected data after the last vertex (the header declares 2 "
                "vertices)");
}

TEST(PlyVertexReader, AsciiBlankLinesAreTolerated) {
  test::TempDir dir;
  const std::string path = dir.file("blank.ply");
  test::writeBytes(path,
                   "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nend_header\n"
                   "1\n\n  \n2\n\n\n");

  const auto values = readColumns(path, {"x"}, 8);

  ASSERT_TRUE(values.has_value()) << values.error().message;
  EXPECT_EQ(*values, (std::vector<double>{1, 2}));
}

struct BadAscii {
  const char* name;
  std::string data;
  std::string message;  // after "PATH: "

  friend void PrintTo(const BadAscii& bad, std::ostream* os) { *os << bad.name; }
};

class PlyAsciiErrors : public ::testing::TestWithParam<BadAscii> {};

TEST_P(PlyAsciiErrors, NameTheLineAndTheProblem) {
  test::TempDir dir;
  const std::string path = dir.file("bad.ply");
  test::writeBytes(path,
                   "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                   "property float z\nend_header\n" +
                       GetParam().data);

  const auto values = readColumns(path, {"x", "y", "z"}, 2);

  ASSERT_FALSE(values.has_value());
  EXPECT_EQ(values.error().code, ErrorCode::kFormat);
  EXPECT_EQ(values.error().message, path + ": " + GetParam().message);
}

INSTANTIATE_TEST_SUITE_P(
    Cases, PlyAsciiErrors,
    ::testing::Values(BadAscii{"TooFew", "1 2 3\n4 5\n7 8 9\n",
                               "line 9: too few values for vertex 2: expected 3, found 2"},
                      BadAscii{"TooMany", "1 2 3\n4 5 6 7\n7 8 9\n",
                               "line 9: too many values for vertex 2: expected 3, found 4"},
                      BadAscii{"NotANumber", "1 abc 3\n",
                               "line 8: vertex 1: value 'abc' of property 'y' is not a number"},
                      BadAscii{"HalfANumber", "1 2 3\n4 5 6\n7 8 9x\n",
                               "line 10: vertex 3: value '9x' of property 'z' is not a number"}),
    [](const ::testing::TestParamInfo<BadAscii>& param_info) {
      return std::string(param_info.param.name);
    });

TEST(PlyVertexReader, FileWithoutVertexElementIsRejected) {
  test::TempDir dir;
  PlyTestFile file;
  PlyTestElement face{"face", {{"int", "vertex_indices", "uchar"}}};
  face.add({0});
  file.elements = {face};
  const std::string path = dir.file("faces.ply");
  test::writePly(path, file);

  const auto ply = PlyVertexReader::open(path);

  ASSERT_FALSE(ply.has_value());
  EXPECT_EQ(ply.error().message, path + ": the header declares no 'vertex' element");
}

TEST(PlyVertexReader, ListPropertiesCannotBeSelected) {
  test::TempDir dir;
  PlyTestFile file;
  PlyTestElement vertex{"vertex", {{"float", "x", ""}, {"int", "ids", "uchar"}}};
  vertex.add({1, 0});
  file.elements = {vertex};
  const std::string path = dir.file("list.ply");
  test::writePly(path, file);
  auto ply = PlyVertexReader::open(path);
  ASSERT_TRUE(ply.has_value()) << ply.error().message;
  const std::size_t list_index = 1;

  const auto selected = ply->selectColumns(std::span<const std::size_t>(&list_index, 1));

  ASSERT_FALSE(selected.has_value());
  EXPECT_EQ(selected.error().code, ErrorCode::kUnsupported);
}

}  // namespace
}  // namespace raymap::io
