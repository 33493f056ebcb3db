// SPDX-License-Identifier: BSD-3-Clause
// Fuzz target: an MCAP file of rosbag2 (records, chunks in zstd/lz4/none, summary, CRCs).
#include <cstddef>
#include <cstdint>

#include "src/bag/bag_reader.hpp"
#include "tests/fuzz/bag_input.hpp"
#include "tests/fuzz/fuzz_input_file.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  auto reader = raymap::bag::openMcap(raymap::fuzz::writeInputFile(data, size, ".mcap"));
  if (reader) {
    raymap::fuzz::readBag(**reader);
  }
  return 0;
}
