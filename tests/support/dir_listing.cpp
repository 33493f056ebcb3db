// SPDX-License-Identifier: BSD-3-Clause
// Folder listings for the tests.
#include "tests/support/dir_listing.hpp"

#include <algorithm>
#include <iterator>
#include <vector>

namespace raymap::test {

std::set<std::string> listFiles(const std::filesystem::path& dir) {
  std::set<std::string> names;
  for (const auto& entry : std::filesystem::recursive_directory_iterator(dir)) {
    names.insert(std::filesystem::relative(entry.path(), dir).string());
  }
  return names;
}

testing::AssertionResult nothingNewIn(const std::filesystem::path& dir,
                                      const std::set<std::string>& before) {
  const std::set<std::string> after = listFiles(dir);
  std::vector<std::string> added;
  std::set_difference(after.begin(), after.end(), before.begin(), before.end(),
                      std::back_inserter(added));
  if (added.empty()) {
    return testing::AssertionSuccess();
  }
  auto failure = testing::AssertionFailure() << "left behind in " << dir.string() << ":";
  for (const std::string& name : added) {
    failure << " " << name;
  }
  return failure;
}

}  // namespace raymap::test
