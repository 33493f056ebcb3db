// SPDX-License-Identifier: BSD-3-Clause
// Byte-plane encoding of a region layer (see region_planes.hpp).
#include "src/map/region_planes.hpp"

#include <cstring>

namespace raymap {

void encodeBytePlanes(const std::byte* src, std::uint32_t voxels, std::uint32_t words_per_voxel,
                      std::byte* out) noexcept {
  const std::size_t n = voxels;
  for (std::uint32_t j = 0; j < words_per_voxel; ++j) {
    std::byte* plane = out + std::size_t{j} * 4u * n;
    for (std::size_t v = 0; v < n; ++v) {
      std::uint32_t word = 0;
      std::memcpy(&word, src + (v * words_per_voxel + j) * 4u, sizeof(word));
      plane[v] = static_cast<std::byte>(word & 0xFFu);
      plane[n + v] = static_cast<std::byte>((word >> 8) & 0xFFu);
      plane[2 * n + v] = static_cast<std::byte>((word >> 16) & 0xFFu);
      plane[3 * n + v] = static_cast<std::byte>(word >> 24);
    }
  }
}

void decodeBytePlanes(const std::byte* in, std::uint32_t voxels, std::uint32_t words_per_voxel,
                      std::byte* dst, bool skip_zero_words) noexcept {
  const std::size_t n = voxels;
  for (std::uint32_t j = 0; j < words_per_voxel; ++j) {
    const std::byte* plane = in + std::size_t{j} * 4u * n;
    for (std::size_t v = 0; v < n; ++v) {
      const std::uint32_t word = std::to_integer<std::uint32_t>(plane[v]) |
                                 std::to_integer<std::uint32_t>(plane[n + v]) << 8 |
                                 std::to_integer<std::uint32_t>(plane[2 * n + v]) << 16 |
                                 std::to_integer<std::uint32_t>(plane[3 * n + v]) << 24;
      if (word != 0 || !skip_zero_words) {
        std::memcpy(dst + (v * words_per_voxel + j) * 4u, &word, sizeof(word));
      }
    }
  }
}

}  // namespace raymap
