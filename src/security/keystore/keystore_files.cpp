// SPDX-License-Identifier: BSD-3-Clause
// Temporary files renamed into place, folders removed on failure, whole-file reads.
#include "src/security/keystore/keystore_files.hpp"

#include <cerrno>
#include <cstdio>
#include <random>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include "platform/errno_text.hpp"

namespace raymap::security {
namespace {

using platform::errnoText;

/// ".NAME.tmp-XXXXXXXX" beside `target` (hidden, so no reader of the folder takes it for a file).
std::filesystem::path temporaryBeside(const std::filesystem::path& target) {
  static thread_local std::mt19937 generator{std::random_device{}()};
  char suffix[16];
  std::snprintf(suffix, sizeof suffix, "%08x", static_cast<unsigned>(generator()));
  std::string name(1, '.');  // (not "." + string: a false -Wrestrict from GCC 12 at -O3)
  name.append(target.filename().string()).append(".tmp-").append(suffix);
  return target.parent_path() / name;
}

Result<void> writeAll(int fd, std::string_view content) {
  std::size_t written = 0;
  while (written < content.size()) {
    const ssize_t n = ::write(fd, content.data() + written, content.size() - written);
    if (n < 0 && errno == EINTR) {
      continue;
    }
    if (n < 0) {
      return fail(ErrorCode::kIo, errnoText(errno));
    }
    written += static_cast<std::size_t>(n);
  }
  if (::fsync(fd) != 0) {
    return fail(ErrorCode::kIo, errnoText(errno));
  }
  return {};
}

/// Creates a new file (never an existing one) with `mode` and writes `content` into it.
Result<void> writeNewFile(const std::filesystem::path& file, std::string_view content,
                          mode_t mode) {
  const int fd = ::open(file.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, mode);
  if (fd < 0) {
    return fail(ErrorCode::kIo, errnoText(errno));
  }
  auto written = writeAll(fd, content);
  const int closed = ::close(fd);
  if (written && closed != 0) {
    written = fail(ErrorCode::kIo, errnoText(errno));
  }
  if (!written) {
    std::error_code ignored;
    std::filesystem::remove(file, ignored);
  }
  return written;
}

}  // namespace

FileBatch::~FileBatch() {
  for (const Entry& entry : entries_) {
    std::error_code ignored;
    std::filesystem::remove(entry.temporary, ignored);
  }
}

Result<void> FileBatch::addFile(const std::filesystem::path& target, std::string_view content,
                                mode_t mode) {
  const std::filesystem::path temporary = temporaryBeside(target);
  if (auto written = writeNewFile(temporary, content, mode); !written) {
    return fail(ErrorCode::kIo, target.string() + ": cannot write: " + written.error().message);
  }
  entries_.push_back({temporary, target, !pathExists(target)});
  return {};
}

Result<void> FileBatch::addLink(const std::filesystem::path& target,
                                const std::filesystem::path& link_to) {
  const std::filesystem::path temporary = temporaryBeside(target);
  if (::symlink(link_to.c_str(), temporary.c_str()) != 0) {
    return fail(ErrorCode::kIo, target.string() + ": cannot make the link to " + link_to.string() +
                                    ": " + errnoText(errno));
  }
  entries_.push_back({temporary, target, !pathExists(target)});
  return {};
}

Result<void> FileBatch::commit() {
  for (std::size_t i = 0; i < entries_.size(); ++i) {
    const Entry& entry = entries_[i];
    if (::rename(entry.temporary.c_str(), entry.target.c_str()) != 0) {
      const std::string message =
          entry.target.string() + ": cannot move into place: " + errnoText(errno);
      for (std::size_t done = 0; done < i; ++done) {
        if (entries_[done].new_path) {
          ::unlink(entries_[done].target.c_str());
        }
      }
      // The destructor removes the temporaries not renamed.
      entries_.erase(entries_.begin(), entries_.begin() + static_cast<std::ptrdiff_t>(i));
      return fail(ErrorCode::kIo, message);
    }
  }
  entries_.clear();
  return {};
}

std::vector<std::filesystem::path> FileBatch::targets() const {
  std::vector<std::filesystem::path> paths;
  for (const Entry& entry : entries_) {
    paths.push_back(entry.target);
  }
  return paths;
}

CreatedFolders::~CreatedFolders() {
  for (auto it = created_.rbegin(); it != created_.rend(); ++it) {
    ::rmdir(it->c_str());  // only when empty: never what someone else put there
  }
}

Result<void> CreatedFolders::create(const std::filesystem::path& folder, mode_t mode) {
  std::filesystem::path prefix;
  std::filesystem::path last = folder.lexically_normal();
  if (!last.has_filename() && last.has_parent_path()) {
    last = last.parent_path();  // "a/b/" -> "a/b"
  }
  for (const std::filesystem::path& part : last) {
    prefix /= part;
    if (part.empty() || part == "/" || part == "." || part == "..") {
      continue;
    }
    const mode_t this_mode = prefix == last ? mode : kFolderMode;
    if (::mkdir(prefix.c_str(), this_mode) == 0) {
      created_.push_back(prefix);
      continue;
    }
    const int error = errno;
    struct stat info {};
    if (error != EEXIST || ::stat(prefix.c_str(), &info) != 0 || !S_ISDIR(info.st_mode)) {
      return fail(ErrorCode::kIo, prefix.string() + ": cannot create the folder: " +
                                      errnoText(error == EEXIST ? ENOTDIR : error));
    }
  }
  return {};
}

bool pathExists(const std::filesystem::path& path) {
  struct stat info {};
  return ::lstat(path.c_str(), &info) == 0;
}

}  // namespace raymap::security
