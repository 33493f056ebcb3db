// SPDX-License-Identifier: BSD-3-Clause
// Fuzz target: a PLY file (ASCII, binary little and big endian; ray and point clouds) read as rays.
#include <cstddef>
#include <cstdint>

#include "tests/fuzz/fuzz_input_file.hpp"
#include "tests/fuzz/ray_source_input.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  raymap::fuzz::readRaySource(raymap::fuzz::writeInputFile(data, size, ".ply"));
  return 0;
}
