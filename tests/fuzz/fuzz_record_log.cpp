// SPDX-License-Identifier: BSD-3-Clause
// Fuzz target: a record log (.rmlog) of raymap record, read to its end.
#include <cstddef>
#include <cstdint>
#include <cstdlib>

#include "src/record/record_log_reader.hpp"
#include "tests/fuzz/fuzz_input_file.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  auto reader =
      raymap::record::RecordLogReader::open(raymap::fuzz::writeInputFile(data, size, ".rmlog"));
  if (!reader) {
    return 0;
  }
  for (int i = 0; i < 100'000; ++i) {
    auto message = (*reader)->next();
    if (!message || !message->has_value()) {
      break;
    }
    if ((*reader)->topic((*message)->topic_id) == nullptr) {
      std::abort();  // a message is only returned on a declared topic
    }
  }
  return 0;
}
