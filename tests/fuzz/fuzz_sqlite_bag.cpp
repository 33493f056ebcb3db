// SPDX-License-Identifier: BSD-3-Clause
// Fuzz target: a SQLite (.db3) file of rosbag2 (its tables as the reader queries them).
#include <cstddef>
#include <cstdint>

#include "src/bag/bag_reader.hpp"
#include "tests/fuzz/bag_input.hpp"
#include "tests/fuzz/fuzz_input_file.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  auto reader = raymap::bag::openSqliteBag(raymap::fuzz::writeInputFile(data, size, ".db3"));
  if (reader) {
    raymap::fuzz::readBag(**reader);
  }
  return 0;
}
