// SPDX-License-Identifier: BSD-3-Clause
// writePng: decoded independently here (chunks, CRCs, inflate, row filters), pixels round-trip,
// bad sizes and unwritable paths fail naming the path and leave nothing behind.
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <optional>
#include <random>
#include <set>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <zlib.h>

#include "src/io/png_writer.hpp"
#include "tests/support/temp_dir.hpp"
#include "tests/unit/io/decoded_png.hpp"

namespace raymap::io::png_test {

namespace {

std::uint32_t be32(const std::vector<std::uint8_t>& bytes, std::size_t at) {
  return std::uint32_t{bytes.at(at)} << 24 | std::uint32_t{bytes.at(at + 1)} << 16 |
         std::uint32_t{bytes.at(at + 2)} << 8 | std::uint32_t{bytes.at(at + 3)};
}

int paeth(int a, int b, int c) {
  const int p = a + b - c;
  const int pa = std::abs(p - a);
  const int pb = std::abs(p - b);
  const int pc = std::abs(p - c);
  if (pa <= pb && pa <= pc) {
    return a;
  }
  return pb <= pc ? b : c;
}

}  // namespace

/// @brief Decodes an 8-bit RGB, non-interlaced PNG written to `path`: checks the signature, every
/// chunk's CRC (zlib crc32), the IHDR fields, that IEND comes last; inflates the concatenated IDAT
/// data (zlib uncompress) and undoes each row's filter (all five PNG filter types). Records a test
/// failure and returns nullopt on any problem. Also used by test_heightmap_export.cpp (same
/// executable).
std::optional<DecodedPng> decodePng(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  const std::vector<std::uint8_t> bytes(std::istreambuf_iterator<char>(in), {});
  const std::vector<std::uint8_t> signature{0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
  if (bytes.size() < signature.size() ||
      !std::equal(signature.begin(), signature.end(), bytes.begin())) {
    ADD_FAILURE() << path << ": no PNG signature";
    return std::nullopt;
  }
  DecodedPng png;
  std::vector<std::uint8_t> idat;
  std::size_t at = signature.size();
  while (at < bytes.size()) {
    if (bytes.size() - at < 12) {
      ADD_FAILURE() << path << ": truncated chunk at byte " << at;
      return std::nullopt;
    }
    const std::uint32_t length = be32(bytes, at);
    if (bytes.size() - at - 12 < length) {
      ADD_FAILURE() << path << ": chunk at byte " << at << " runs past the end";
      return std::nullopt;
    }
    const std::string type(bytes.begin() + static_cast<std::ptrdiff_t>(at + 4),
                           bytes.begin() + static_cast<std::ptrdiff_t>(at + 8));
    const std::uint8_t* data = bytes.data() + at + 8;
    const uLong crc = ::crc32(::crc32(0L, bytes.data() + at + 4, 4), data, length);
    if (be32(bytes, at + 8 + length) != static_cast<std::uint32_t>(crc)) {
      ADD_FAILURE() << path << ": bad CRC in chunk " << type;
      return std::nullopt;
    }
    png.chunk_types.push_back(type);
    if (type == "IHDR") {
      if (length != 13) {
        ADD_FAILURE() << path << ": IHDR of " << length << " bytes";
        return std::nullopt;
      }
      const std::vector<std::uint8_t> header(data, data + 13);
      png.width = static_cast<int>(be32(header, 0));
      png.height = static_cast<int>(be32(header, 4));
      const std::vector<std::uint8_t> rest(header.begin() + 8, header.end());
      if (rest != std::vector<std::uint8_t>{8, 2, 0, 0, 0}) {
        ADD_FAILURE() << path << ": not 8-bit RGB, deflate, adaptive filters, non-interlaced";
        return std::nullopt;
      }
    } else if (type == "IDAT") {
      idat.insert(idat.end(), data, data + length);
    }
    at += 12 + length;
  }
  if (png.chunk_types.empty() || png.chunk_types.front() != "IHDR" ||
      png.chunk_types.back() != "IEND") {
    ADD_FAILURE() << path << ": IHDR must come first and IEND last";
    return std::nullopt;
  }

  const std::size_t stride = static_cast<std::size_t>(png.width) * 3;
  std::vector<std::uint8_t> raw((stride + 1) * static_cast<std::size_t>(png.height));
  uLongf raw_size = raw.size();
  if (uncompress(raw.data(), &raw_size, idat.data(), idat.size()) != Z_OK ||
      raw_size != raw.size()) {
    ADD_FAILURE() << path << ": IDAT does not inflate to " << raw.size() << " bytes";
    return std::nullopt;
  }
  png.rgb.resize(stride * static_cast<std::size_t>(png.height));
  for (std::size_t y = 0; y < static_cast<std::size_t>(png.height); ++y) {
    const int filter = raw[y * (stride + 1)];
    png.filters.insert(filter);
    const std::uint8_t* in_row = raw.data() + y * (stride + 1) + 1;
    std::uint8_t* row = png.rgb.data() + y * stride;
    const std::uint8_t* prior = y > 0 ? row - stride : nullptr;
    for (std::size_t k = 0; k < stride; ++k) {
      const int a = k >= 3 ? row[k - 3] : 0;
      const int b = prior != nullptr ? prior[k] : 0;
      const int c = prior != nullptr && k >= 3 ? prior[k - 3] : 0;
      int predictor = 0;
      switch (filter) {
        case 0:
          break;
        case 1:
          predictor = a;
          break;
        case 2:
          predictor = b;
          break;
        case 3:
          predictor = (a + b) / 2;
          break;
        case 4:
          predictor = paeth(a, b, c);
          break;
        default:
          ADD_FAILURE() << path << ": row " << y << " has filter type " << filter;
          return std::nullopt;
      }
      row[k] = static_cast<std::uint8_t>(in_row[k] + predictor);
    }
  }
  return png;
}

namespace {

using test::TempDir;

std::vector<std::uint8_t> gradient(int width, int height) {
  std::vector<std::uint8_t> rgb;
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      rgb.push_back(static_cast<std::uint8_t>(x * 37));
      rgb.push_back(static_cast<std::uint8_t>(y * 53));
      rgb.push_back(static_cast<std::uint8_t>(x * y + 11));
    }
  }
  return rgb;
}

TEST(PngWriter, PixelsRoundTripThroughAnIndependentDecoder) {
  // Arrange
  TempDir dir;
  const std::string path = dir.file("small.png");
  const std::vector<std::uint8_t> rgb = gradient(7, 5);

  // Act
  auto written = writePng(path, 7, 5, rgb);

  // Assert
  ASSERT_TRUE(written.has_value()) << written.error().message;
  const auto png = decodePng(path);
  ASSERT_TRUE(png.has_value());
  EXPECT_EQ(png->width, 7);
  EXPECT_EQ(png->height, 5);
  EXPECT_EQ(png->rgb, rgb);
  EXPECT_EQ(png->chunk_types, (std::vector<std::string>{"IHDR", "IDAT", "IEND"}));
}

TEST(PngWriter, OnePixelImage) {
  // Arrange
  TempDir dir;
  const std::string path = dir.file("one.png");
  const std::vector<std::uint8_t> rgb{1, 2, 3};

  // Act
  auto written = writePng(path, 1, 1, rgb);

  // Assert
  ASSERT_TRUE(written.has_value()) << written.error().message;
  const auto png = decodePng(path);
  ASSERT_TRUE(png.has_value());
  EXPECT_EQ(png->rgb, rgb);
}

TEST(PngWriter, IncompressibleDataSpansSeveralIdatChunks) {
  // Arrange: noise does not compress, so 700 x 700 x 3 bytes need more than one 1 MiB chunk.
  TempDir dir;
  const std::string path = dir.file("noise.png");
  std::mt19937 random(42);
  std::vector<std::uint8_t> rgb(700 * 700 * 3);
  for (std::uint8_t& byte : rgb) {
    byte = static_cast<std::uint8_t>(random());
  }

  // Act
  auto written = writePng(path, 700, 700, rgb);

  // Assert
  ASSERT_TRUE(written.has_value()) << written.error().message;
  const auto png = decodePng(path);
  ASSERT_TRUE(png.has_value());
  EXPECT_EQ(png->rgb, rgb);
  EXPECT_GE(std::count(png->chunk_types.begin(), png->chunk_types.end(), "IDAT"), 2);
}

TEST(PngWriter, RepeatedRowsAreFilteredUpAndCompressSmall) {
  // Arrange: 400 x 400 of 100-pixel blocks, like a rendered height map.
  TempDir dir;
  const std::string path = dir.file("blocks.png");
  std::vector<std::uint8_t> rgb;
  for (int y = 0; y < 400; ++y) {
    for (int x = 0; x < 400; ++x) {
      const int block = (x / 100) + 4 * (y / 100);
      rgb.push_back(static_cast<std::uint8_t>(block * 16));
      rgb.push_back(static_cast<std::uint8_t>(255 - block * 16));
      rgb.push_back(static_cast<std::uint8_t>(block * 7));
    }
  }

  // Act
  auto written = writePng(path, 400, 400, rgb);

  // Assert
  ASSERT_TRUE(written.has_value()) << written.error().message;
  const auto png = decodePng(path);
  ASSERT_TRUE(png.has_value());
  EXPECT_EQ(png->rgb, rgb);
  EXPECT_TRUE(png->filters.count(2) == 1) << "no row used the Up filter";
  EXPECT_LT(std::filesystem::file_size(path), 8000u);
}

TEST(PngWriter, ReplacesAnExistingFileAndLeavesNoTemporary) {
  // Arrange
  TempDir dir;
  const std::string path = dir.file("image.png");
  std::ofstream(path) << "old contents";
  const std::vector<std::uint8_t> rgb = gradient(3, 2);

  // Act
  auto written = writePng(path, 3, 2, rgb);

  // Assert
  ASSERT_TRUE(written.has_value()) << written.error().message;
  const auto png = decodePng(path);
  ASSERT_TRUE(png.has_value());
  EXPECT_EQ(png->rgb, rgb);
  EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir.path()),
                          std::filesystem::directory_iterator()),
            1);
}

TEST(PngWriter, AnUnwritablePathFailsNamingItAndLeavesNothing) {
  // Arrange
  TempDir dir;
  const std::string path = dir.file("missing/image.png");

  // Act
  auto written = writePng(path, 2, 2, gradient(2, 2));

  // Assert
  ASSERT_FALSE(written.has_value());
  EXPECT_EQ(written.error().code, ErrorCode::kIo);
  EXPECT_NE(written.error().message.find(path), std::string::npos) << written.error().message;
  EXPECT_TRUE(std::filesystem::is_empty(dir.path()));
}

TEST(PngWriter, BadSizesAreRejectedBeforeAnythingIsWritten) {
  // Arrange
  TempDir dir;
  const std::string path = dir.file("bad.png");
  const std::vector<std::uint8_t> rgb = gradient(4, 5);  // 60 bytes: room for every case
  struct Case {
    int width;
    int height;
    std::size_t bytes;
  };

  for (const Case c : {Case{0, 4, 0}, Case{4, 0, 0}, Case{-1, 4, 12}, Case{4, 4, 47},
                       Case{4, 4, 49}, Case{kMaxPngSide + 1, 1, 48}}) {
    // Act
    auto written =
        writePng(path, c.width, c.height, std::span<const std::uint8_t>(rgb).first(c.bytes));

    // Assert
    ASSERT_FALSE(written.has_value()) << c.width << " x " << c.height << ", " << c.bytes;
    EXPECT_EQ(written.error().code, ErrorCode::kInvalidArgument);
    EXPECT_NE(written.error().message.find(path), std::string::npos) << written.error().message;
  }
  EXPECT_TRUE(std::filesystem::is_empty(dir.path()));
}

}  // namespace
}  // namespace raymap::io::png_test
