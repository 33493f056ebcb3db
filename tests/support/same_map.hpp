// SPDX-License-Identifier: BSD-3-Clause
// Two map files that must hold the same map: what `raymap populate` wrote and what the library
// (raymap::Mapper) saved from the same input and options.
#pragma once

#include <string>

namespace raymap::test {

/// @brief Expects (gtest) the same mode, parameters and regions, and the same bytes in every
/// layer of every region; the files' provenance (source, created_by) may differ.
void expectSameMap(const std::string& cli, const std::string& library);

}  // namespace raymap::test
