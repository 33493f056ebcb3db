// SPDX-License-Identifier: BSD-3-Clause
// Reads a fuzzed bag file to its end, as raymap populate and replay do.
#pragma once

#include <memory>

#include "src/bag/bag_reader.hpp"

namespace raymap::fuzz {

/// @brief Reads every message of an opened bag (bounded), twice (rewind()), and its statistics.
void readBag(bag::BagReader& reader);

}  // namespace raymap::fuzz
