// SPDX-License-Identifier: BSD-3-Clause
// A region's voxels as byte planes: the representation both the map file and the cold tiers
// compress, because it turns a layer's words into long runs of equal bytes.
#pragma once

#include <cstddef>
#include <cstdint>

namespace raymap {

/// @brief Writes one layer of one region as byte planes: for each 32-bit word j of a voxel, for
/// each byte significance b (0 = least significant), byte b of word j of every voxel, in voxel
/// index order. `src` holds `voxels` voxels of `words_per_voxel` native 32-bit words; `out` takes
/// voxels * words_per_voxel * 4 bytes. Reading whole native words and shifting makes the planes
/// independent of the host's byte order (docs/map-format.md).
///
/// Splitting words into planes is what makes a general-purpose compressor effective on voxels:
/// the high bytes of counts and the exponent bytes of log-odds are long runs of one value.
/// Thread-safety: pure function. Real-time: allocation-free.
void encodeBytePlanes(const std::byte* src, std::uint32_t voxels, std::uint32_t words_per_voxel,
                      std::byte* out) noexcept;

/// @brief Inverse of encodeBytePlanes(): `in` holds the planes, `dst` takes the native words.
/// `skip_zero_words`: `dst` already reads as zeros, and words that are zero are not written, so
/// that pages of `dst` no non-zero word falls in are never touched (and never become resident).
void decodeBytePlanes(const std::byte* in, std::uint32_t voxels, std::uint32_t words_per_voxel,
                      std::byte* dst, bool skip_zero_words = false) noexcept;

}  // namespace raymap
