// SPDX-License-Identifier: BSD-3-Clause
// Fuzz target: a map file (.rmap): header, region index and every layer's blocks.
#include <cstddef>
#include <cstdint>

#include "src/io/map_file.hpp"
#include "tests/fuzz/fuzz_input_file.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string& path = raymap::fuzz::writeInputFile(data, size, ".rmap");
  (void)raymap::io::readMapHeader(path);
  // The budget bounds what a header may claim (a real map of 64 MiB is plenty for the seeds):
  // more regions than that are refused before anything is allocated.
  raymap::io::MapLoadOptions options;
  options.memory_budget_bytes = std::uint64_t{64} << 20;
  (void)raymap::io::loadMap(path, options);
  return 0;
}
