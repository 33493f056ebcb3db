// SPDX-License-Identifier: BSD-3-Clause
// The header.frame_id buffer every preallocated outgoing message keeps.
#pragma once

#include <cstddef>

namespace raymap::dds {

/// @brief Copies `text` (NUL-terminated; null = "") into a fixed text slot of `slot_bytes`,
/// truncated to slot_bytes - 1 characters and always NUL-terminated. @pre slot_bytes > 0.
/// @rt allocates: no.
inline void copyText(char* slot, std::size_t slot_bytes, const char* text) noexcept {
  std::size_t length = 0;
  if (text != nullptr) {
    while (length + 1 < slot_bytes && text[length] != '\0') {
      slot[length] = text[length];
      ++length;
    }
  }
  slot[length] = '\0';
}

/// @brief Copies `frame` into a message's frame buffer (copyText with the buffer's size).
template <std::size_t N>
void copyFrameId(char (&out)[N], const char* frame) noexcept {
  copyText(out, N, frame);
}

}  // namespace raymap::dds
