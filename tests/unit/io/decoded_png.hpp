// SPDX-License-Identifier: BSD-3-Clause
// A PNG file read back and checked by the tests' own decoder (test_png_writer.cpp defines it; the
// height-map export tests use it too).
#pragma once

#include <cstdint>
#include <optional>
#include <set>
#include <string>
#include <vector>

namespace raymap::io::png_test {

/// A PNG read back by decodePng(). Value type.
struct DecodedPng {
  int width = 0;
  int height = 0;
  std::vector<std::uint8_t> rgb;         ///< rows top to bottom, R G B
  std::vector<std::string> chunk_types;  ///< in file order
  std::set<int> filters;                 ///< row filter types seen
};

/// @brief Decodes and checks a PNG file: the signature, every chunk's CRC, the IHDR fields, IEND
/// last, the image data inflated and unfiltered. nullopt (and a test failure) when it is invalid.
std::optional<DecodedPng> decodePng(const std::string& path);

}  // namespace raymap::io::png_test
