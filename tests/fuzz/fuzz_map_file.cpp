// SPDX-License-Identifier: BSD-3-Clause
// Fuzz target: a map file (.rmap): header, region index and every layer's blocks.
#include <cstddef>
#include <cstdint>

#include "src/io/map_file.hpp"
#include "tests/fuzz/fuzz_input_file.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string& path = raymap::fuzz::writeInputFile(data, size, ".rmap");
  (void)raymap::io::readMapHeader(path);
  // The default budget: just the file's own regions (a pool sized by what the header claims, so
  // a claim the file cannot back must be refused before it is allocated; -malloc_limit_mb
  // catches one that is not). A fixed large budget would allocate it for every input.
  (void)raymap::io::loadMap(path);
  return 0;
}
