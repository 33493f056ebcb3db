// SPDX-License-Identifier: BSD-3-Clause
// Temporary names "<path>.raymap-tmp-<pid>" and the removal of those whose process is gone.
#include "src/io/temp_files.hpp"

#include <cerrno>
#include <charconv>
#include <climits>
#include <cstring>
#include <filesystem>
#include <system_error>

#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include "platform/errno_text.hpp"

namespace raymap::io {
namespace {

/// The process id a temporary name ends with, or 0 when the rest of the name is not a pid as
/// temporaryPathFor() writes it (decimal, no sign or leading zero, within pid_t).
pid_t pidOfSuffix(std::string_view digits) noexcept {
  if (digits.empty() || digits.front() == '0') {
    return 0;
  }
  long long value = 0;
  const auto [end, error] = std::from_chars(digits.data(), digits.data() + digits.size(), value);
  if (error != std::errc() || end != digits.data() + digits.size() || value <= 0 ||
      value > INT_MAX) {
    return 0;
  }
  return static_cast<pid_t>(value);
}

/// kill(pid, 0) sends nothing and reports whether the process exists: EPERM means it does (but
/// belongs to another user), ESRCH that it does not.
bool processExists(pid_t pid) noexcept { return ::kill(pid, 0) == 0 || errno == EPERM; }

}  // namespace

std::string temporaryPathFor(const std::string& path) {
  return path + std::string(kTemporaryInfix) + std::to_string(::getpid());
}

bool isOwnTemporaryPath(std::string_view path) noexcept {
  const std::size_t at = path.rfind(kTemporaryInfix);
  if (at == std::string_view::npos || at == 0) {
    return false;
  }
  return pidOfSuffix(path.substr(at + kTemporaryInfix.size())) == ::getpid();
}

StaleTemporaries removeStaleTemporaries(const std::string& path) {
  namespace fs = std::filesystem;
  StaleTemporaries result;
  const fs::path output(path);
  const std::string prefix = output.filename().string() + std::string(kTemporaryInfix);
  if (output.filename().empty()) {
    return result;
  }
  const fs::path directory = output.has_parent_path() ? output.parent_path() : fs::path(".");
  std::error_code error;
  fs::directory_iterator entries(directory, error);
  if (error) {
    return result;  // a missing or unreadable directory fails later, where the output is written
  }
  for (const fs::directory_entry& entry : entries) {
    const std::string name = entry.path().filename().string();
    if (name.size() <= prefix.size() || name.compare(0, prefix.size(), prefix) != 0) {
      continue;
    }
    const pid_t pid = pidOfSuffix(std::string_view(name).substr(prefix.size()));
    if (pid == 0 || pid == ::getpid() || processExists(pid)) {
      continue;
    }
    // lstat: a symbolic link or a directory of that name is not a file raymap wrote.
    struct stat info {};
    if (::lstat(entry.path().c_str(), &info) != 0 || !S_ISREG(info.st_mode)) {
      continue;
    }
    const std::string stale =
        output.has_parent_path() ? (output.parent_path() / name).string() : name;
    if (::unlink(stale.c_str()) == 0) {
      result.removed.push_back(stale);
    } else {
      result.errors.push_back(stale + ": " + platform::errnoText(errno));
    }
  }
  return result;
}

}  // namespace raymap::io
