// SPDX-License-Identifier: BSD-3-Clause
// Several output files of one command that appear together or not at all.
#pragma once

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <string>
#include <utility>
#include <vector>

#include "raymap/error.hpp"
#include <unistd.h>

namespace raymap::cli {

/// Output files written under temporary names ("<path>.part-<pid>") and renamed together by
/// commit(); whatever was not committed is removed on destruction.
class StagedOutputs {
 public:
  StagedOutputs() = default;
  StagedOutputs(const StagedOutputs&) = delete;
  StagedOutputs& operator=(const StagedOutputs&) = delete;
  ~StagedOutputs() {
    for (const auto& [final_path, temp_path] : files_) {
      std::remove(temp_path.c_str());
    }
  }
  /// @brief The temporary path to write `final_path` to.
  std::string add(const std::string& final_path) {
    files_.emplace_back(final_path, final_path + ".part-" + std::to_string(::getpid()));
    return files_.back().second;
  }
  Expected<void, Error> commit() {
    for (const auto& [final_path, temp_path] : files_) {
      if (std::rename(temp_path.c_str(), final_path.c_str()) != 0) {
        return fail(ErrorCode::kIo, "cannot replace '" + final_path + "': " + std::strerror(errno));
      }
    }
    files_.clear();
    return {};
  }

 private:
  std::vector<std::pair<std::string, std::string>> files_;
};

}  // namespace raymap::cli
