// SPDX-License-Identifier: BSD-3-Clause
// The flags raymap shows for the library's configuration keys (tools/raymap/option_names.cpp)
// are flags raymap has, spelt as its --help spells them.
#include <string>
#include <string_view>

#include <gtest/gtest.h>

#include "tests/support/cli_runner.hpp"
#include "tools/raymap/option_names.hpp"

namespace raymap::test {
namespace {

/// `flag` stands in `help` as a whole option name ("--max-range", not "--max-range-x").
bool namesOption(const std::string& help, std::string_view flag) {
  for (std::size_t at = help.find(flag); at != std::string::npos; at = help.find(flag, at + 1)) {
    const std::size_t end = at + flag.size();
    if (end == help.size() ||
        (help[end] != '-' && help[end] != '_' && (help[end] < 'a' || help[end] > 'z'))) {
      return true;
    }
  }
  return false;
}

TEST(CliOptionNames, EveryFlagShownForAKeyIsAnOptionOfRaymap) {
  std::string help;
  for (const char* command : {"populate", "heightmap", "export", "replay", "record"}) {
    const RunResult r = runRaymap({command, "--help"});
    ASSERT_EQ(r.exit_code, 0) << describe(r);
    help += r.out;
  }
  for (const cli::OptionFlag& row : cli::optionFlags()) {
    // "populate --mode" names the command too: the option is what follows it.
    const std::string_view flag = row.flag.substr(row.flag.find("--"));
    EXPECT_TRUE(namesOption(help, flag)) << row.key << " -> " << row.flag;
  }
}

}  // namespace
}  // namespace raymap::test
