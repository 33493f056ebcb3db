// SPDX-License-Identifier: BSD-3-Clause
// What a folder holds, for the tests of commands that must leave nothing behind when they fail.
#pragma once

#include <filesystem>
#include <set>
#include <string>

#include <gtest/gtest.h>

namespace raymap::test {

/// @brief Every path under `dir` (recursively), relative to it.
std::set<std::string> listFiles(const std::filesystem::path& dir);

/// @brief Fails unless `dir` holds exactly the paths `before` listed (listFiles()): no output,
/// no temporary, no probe file left behind; names every path that is new.
testing::AssertionResult nothingNewIn(const std::filesystem::path& dir,
                                      const std::set<std::string>& before);

}  // namespace raymap::test
