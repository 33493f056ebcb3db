// SPDX-License-Identifier: BSD-3-Clause
// The one name raymap gives a file it is still writing, and the clean-up of such files that a
// killed process left behind.
#pragma once

#include <string>
#include <string_view>
#include <vector>

namespace raymap::io {

/// Between an output's name and the writing process's id: "<path>.raymap-tmp-<pid>". Specific
/// enough that nothing but raymap makes such names, so the clean-up below never touches another
/// program's files.
inline constexpr std::string_view kTemporaryInfix = ".raymap-tmp-";

/// @brief The temporary name of `path` for this process: "<path>.raymap-tmp-<getpid()>".
std::string temporaryPathFor(const std::string& path);

/// @brief True when `path` is a temporary name of this process (ends in kTemporaryInfix and
/// getpid()): its owner renames it into place, so a writer given it writes it in place.
bool isOwnTemporaryPath(std::string_view path) noexcept;

/// @brief What removeStaleTemporaries() did: the files removed, and why others could not be.
struct StaleTemporaries {
  std::vector<std::string> removed;
  std::vector<std::string> errors;  ///< "PATH: reason" for each that could not be removed
};

/// @brief Removes the temporaries of `path` ("<path>.raymap-tmp-<pid>" in its directory) whose
/// process no longer exists: what a killed (SIGKILL, power loss) raymap left. Only regular files
/// of exactly that pattern are removed; those of a live process (a concurrent writer, or this
/// process) are kept. Never fails: a directory that cannot be read has nothing to report.
StaleTemporaries removeStaleTemporaries(const std::string& path);

}  // namespace raymap::io
