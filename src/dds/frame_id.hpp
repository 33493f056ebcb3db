// SPDX-License-Identifier: BSD-3-Clause
// The header.frame_id buffer every preallocated outgoing message keeps.
#pragma once

#include <cstddef>

namespace raymap::dds {

/// @brief Copies `frame` (NUL-terminated; null = "") into a message's frame buffer, truncated to
/// N - 1 characters and always NUL-terminated. @rt allocates: no.
template <std::size_t N>
void copyFrameId(char (&out)[N], const char* frame) noexcept {
  std::size_t length = 0;
  if (frame != nullptr) {
    while (length + 1 < N && frame[length] != '\0') {
      out[length] = frame[length];
      ++length;
    }
  }
  out[length] = '\0';
}

}  // namespace raymap::dds
