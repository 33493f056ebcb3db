// SPDX-License-Identifier: BSD-3-Clause
// Fuzz target: the PLY header parser on arbitrary text (every keyword, type and count).
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string_view>

#include "src/io/ply_header.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  auto header = raymap::io::parsePlyHeader(text, "fuzz.ply");
  if (header && header->header_bytes > size) {
    std::abort();  // a header cannot be longer than the text it was read from
  }
  return 0;
}
