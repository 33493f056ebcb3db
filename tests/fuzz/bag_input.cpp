// SPDX-License-Identifier: BSD-3-Clause
// Reads a fuzzed bag to its end.
#include "tests/fuzz/bag_input.hpp"

#include <cstdlib>

namespace raymap::fuzz {

void readBag(bag::BagReader& reader) {
  (void)reader.statistics();
  const auto topics = reader.topics().size();
  for (int pass = 0; pass < 2; ++pass) {
    std::uint64_t seen = 0;
    auto done = reader.forEach([&](const bag::BagMessage& message) {
      if (message.topic >= topics) {
        std::abort();  // a message is only handed out on a known topic
      }
      return ++seen < 100'000;
    });
    if (!done) {
      return;
    }
  }
}

}  // namespace raymap::fuzz
