// SPDX-License-Identifier: BSD-3-Clause
// A unique temporary directory for one test, removed with everything in it afterwards.
#pragma once

#include <filesystem>
#include <string>

namespace raymap::test {

/// @brief Creates a fresh directory under $TMPDIR (or /tmp); removes it in the destructor.
class TempDir {
 public:
  TempDir();
  ~TempDir();
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;

  const std::filesystem::path& path() const noexcept { return path_; }
  /// @brief Path of a file inside the directory.
  std::string file(const std::string& name) const { return (path_ / name).string(); }

 private:
  std::filesystem::path path_;
};

/// @brief Directory of the shared real data (../shared/data), or empty when it is absent.
std::filesystem::path sharedDataDir();

}  // namespace raymap::test
