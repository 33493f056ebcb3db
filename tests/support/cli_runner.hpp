// SPDX-License-Identifier: BSD-3-Clause
// Running the raymap program from tests: its exit code, stdout and stderr.
#pragma once
#include <optional>
#include <string>
#include <vector>

#include <gtest/gtest.h>

namespace raymap::test {

/// What one run of the program did.
struct RunResult {
  int exit_code = -1;  ///< exit status, or 128 + signal number when it was killed
  std::string out;
  std::string err;
};

/// @brief Runs the raymap binary (RAYMAP_CLI_PATH) with `args`, capturing its exit code, stdout
/// and stderr (read as they fill, so a chatty child never blocks). A failure to start is a test
/// failure.
RunResult runRaymap(const std::vector<std::string>& args);
/// @brief Runs any program (`words[0]`, looked up in PATH like a shell does) the same way.
RunResult runProgram(std::vector<std::string> words);

/// @brief A run for failure messages: exit code, stdout and stderr.
std::string describe(const RunResult& r);

/// @brief Success when `text` contains `part`; the failure shows the whole text.
testing::AssertionResult contains(const std::string& text, const std::string& part);

/// @brief The whole content of a file ("" when it cannot be read).
std::string readFile(const std::string& path);
/// @brief Writes `text` to `path` (a test failure when it cannot).
void writeText(const std::string& path, const std::string& text);

/// @brief `a` followed by `b` (command-line arguments).
std::vector<std::string> concat(std::vector<std::string> a, const std::vector<std::string>& b);

/// @brief The first value of member `key` anywhere in the JSON document `json` (document order):
/// a string's text, or any other value as JSON text (a number, `true`, `null`); nullopt when no
/// member has that name. Text that is not JSON is a test failure (parseJson).
std::optional<std::string> jsonValue(const std::string& json, const std::string& key);

/// @brief Why `--backend <device>` cannot run here, or "" when it can (as `raymap devices` says;
/// the CPU always can).
std::string deviceUnavailable(const std::string& device);

}  // namespace raymap::test
