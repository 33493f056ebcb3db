// SPDX-License-Identifier: BSD-3-Clause
// A PNG file read back with libpng, as the tests see an image: its size, its pixel format and
// its pixels, whatever encoder wrote it and however it compressed them.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace raymap::test {

/// A PNG as decoded by decodePng(): the image, not the bytes of the file. Value type.
struct DecodedPng {
  int width = 0;        ///< pixels
  int height = 0;       ///< pixels
  int bit_depth = 0;    ///< bits per sample (8 for raymap's images)
  int colour_type = 0;  ///< PNG colour type: 2 = truecolour (RGB)
  int interlace = 0;    ///< 0 = none, 1 = Adam7
  /// The rows top to bottom as they are stored, unfiltered and uncompressed, with no padding
  /// between them: for 8-bit RGB, R G B for each pixel left to right.
  std::vector<std::uint8_t> pixels;
};

/// @brief Decodes the PNG file at `path` with libpng, checking every chunk's CRC and the zlib
/// stream's Adler-32 as it reads (no transformation: the samples as stored).
/// @return the image, or nullopt (and a test failure naming the path) when the file cannot be
/// read or is not a valid PNG.
std::optional<DecodedPng> decodePng(const std::string& path);

/// @brief A byte string that is the same for two PNGs exactly when their images are: the
/// header "PNG <width> <height> <bit depth> <colour type> <interlace>\n", then the pixels.
std::string decodedPngBytes(const DecodedPng& png);

}  // namespace raymap::test
