// SPDX-License-Identifier: BSD-3-Clause
// writePng: the image read back with libpng has the size, pixel format and pixels written (chunk
// CRCs and the zlib stream are checked as libpng reads), compression keeps blocky images small,
// bad sizes and unwritable paths fail naming the path and leave nothing behind.
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "src/io/png_writer.hpp"
#include "tests/support/decoded_png.hpp"
#include "tests/support/temp_dir.hpp"

namespace raymap::io {
namespace {

using test::DecodedPng;
using test::decodePng;
using test::TempDir;

constexpr int kRgbColourType = 2;  // PNG colour type: truecolour, no alpha

/// Expects an 8-bit RGB, non-interlaced image of `width` x `height` holding `rgb`.
void expectImage(const std::optional<DecodedPng>& png, int width, int height,
                 const std::vector<std::uint8_t>& rgb) {
  ASSERT_TRUE(png.has_value());
  EXPECT_EQ(png->width, width);
  EXPECT_EQ(png->height, height);
  EXPECT_EQ(png->bit_depth, 8);
  EXPECT_EQ(png->colour_type, kRgbColourType);
  EXPECT_EQ(png->interlace, 0);
  EXPECT_TRUE(png->pixels == rgb) << "the pixels differ";
}

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

TEST(PngWriter, PixelsRoundTripThroughLibpng) {
  // Arrange
  TempDir dir;
  const std::string path = dir.file("small.png");
  const std::vector<std::uint8_t> rgb = gradient(7, 5);

  // Act
  auto written = writePng(path, 7, 5, rgb);

  // Assert
  ASSERT_TRUE(written.has_value()) << written.error().message;
  expectImage(decodePng(path), 7, 5, rgb);
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
  expectImage(decodePng(path), 1, 1, rgb);
}

TEST(PngWriter, IncompressibleNoiseRoundTrips) {
  // Arrange: noise does not compress: 1.4 MiB of image data, in many IDAT chunks.
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
  expectImage(decodePng(path), 700, 700, rgb);
}

TEST(PngWriter, BlockyImagesCompressSmall) {
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
  expectImage(decodePng(path), 400, 400, rgb);
  EXPECT_LT(std::filesystem::file_size(path), 8000u);  // of 480,000 bytes of pixels
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
  expectImage(decodePng(path), 3, 2, rgb);
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
}  // namespace raymap::io
