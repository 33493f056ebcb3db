// SPDX-License-Identifier: BSD-3-Clause
// Fuzz target: a gzip-compressed PLY file (.ply.gz) read as rays: the gzip layer and the PLY under
// it.
#include <cstddef>
#include <cstdint>

#include "tests/fuzz/fuzz_input_file.hpp"
#include "tests/fuzz/ray_source_input.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  raymap::fuzz::readRaySource(raymap::fuzz::writeInputFile(data, size, ".ply.gz"));
  return 0;
}
