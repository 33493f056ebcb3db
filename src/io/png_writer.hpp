// SPDX-License-Identifier: BSD-3-Clause
// Writing an 8-bit RGB image as a PNG file, encoded by libpng.
#pragma once

#include <cstdint>
#include <span>
#include <string>

#include "raymap/error.hpp"

namespace raymap::io {

/// Largest width or height writePng() accepts, pixels (keeps the raw image under 2 GiB per side
/// squared well before zlib's or PNG's own limits).
inline constexpr int kMaxPngSide = 32768;

/// @brief Writes an 8-bit RGB, non-interlaced PNG through a temporary file and rename (readers see
/// the old file or the complete new one; nothing is left behind on failure).
/// @param[in] path destination file.
/// @param[in] width, height image size in pixels, 1 to kMaxPngSide.
/// @param[in] rgb width * height * 3 bytes: rows top to bottom, pixels left to right, R G B.
/// @return nothing, or an Error naming the path: kInvalidArgument for a bad size or a buffer of
/// the wrong length, kIo when the file cannot be written, kCapacity when encoding fails (libpng
/// out of memory; the message gives libpng's reason).
Expected<void, Error> writePng(const std::string& path, int width, int height,
                               std::span<const std::uint8_t> rgb);

}  // namespace raymap::io
