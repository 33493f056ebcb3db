// SPDX-License-Identifier: BSD-3-Clause
// StagedOutputs: refuse outputs that are inputs, create temporaries up front, rename together.
#include "src/io/staged_outputs.hpp"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <set>
#include <system_error>
#include <utility>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include "platform/errno_text.hpp"
#include "platform/interrupt_cleanup.hpp"
#include "src/io/temp_files.hpp"

namespace raymap::io {
namespace {

namespace fs = std::filesystem;

/// True when both name one existing file: the same inode, whatever the spelling, symbolic links
/// or hard links.
bool sameExistingFile(const std::string& a, const std::string& b) {
  std::error_code error;
  return fs::equivalent(a, b, error) && !error;
}

/// True when two output paths end up as the same file: equal once made absolute and normal
/// (the files need not exist yet), with symbolic links of their directories resolved, or the
/// same existing file.
bool sameOutput(const std::string& a, const std::string& b) {
  std::error_code error_a;
  std::error_code error_b;
  const fs::path canonical_a = fs::weakly_canonical(fs::absolute(a), error_a);
  const fs::path canonical_b = fs::weakly_canonical(fs::absolute(b), error_b);
  if (!error_a && !error_b && canonical_a == canonical_b) {
    return true;
  }
  return fs::absolute(a).lexically_normal() == fs::absolute(b).lexically_normal() ||
         sameExistingFile(a, b);
}

/// The directory an output is renamed in, to flush its new entry to disk.
std::string directoryOf(const std::string& path) {
  const fs::path parent = fs::path(path).parent_path();
  return parent.empty() ? std::string(".") : parent.string();
}

}  // namespace

StagedOutputs::StagedOutputs(std::string command) : command_(std::move(command)) {}

StagedOutputs::~StagedOutputs() { removeAll(); }

void StagedOutputs::removeAll() noexcept {
  for (const Output& output : outputs_) {
    ::unlink(output.temp.c_str());
    // After the unlink: a signal meanwhile still finds the file to remove.
    platform::InterruptCleanup::remove(output.signal_slot);
  }
  outputs_.clear();
}

void StagedOutputs::input(const std::string& path, const std::string& what) {
  if (path.empty() || path == "-") {
    return;
  }
  inputs_.push_back(Input{path, what});
  // A directory input (a rosbag2 bag) is read through the files in it.
  std::error_code error;
  if (fs::is_directory(path, error)) {
    for (const fs::directory_entry& entry : fs::directory_iterator(path, error)) {
      inputs_.push_back(Input{entry.path().string(), what});
    }
  }
}

Result<std::string> StagedOutputs::add(const std::string& path, const std::string& option) {
  for (const Input& in : inputs_) {
    if (sameExistingFile(path, in.path)) {
      return fail(ErrorCode::kInvalidArgument,
                  option + " '" + path + "' is the same file as " + in.what + " '" + in.path +
                      "': raymap does not overwrite its inputs; choose another output");
    }
  }
  for (const Output& other : outputs_) {
    if (sameOutput(path, other.path)) {
      return fail(ErrorCode::kInvalidArgument, option + " '" + path + "' is also the file of " +
                                                   other.option + " '" + other.path +
                                                   "': each output needs a file of its own");
    }
  }
  struct stat info {};
  if (::stat(path.c_str(), &info) == 0 && S_ISDIR(info.st_mode)) {
    return fail(ErrorCode::kIo, option + ": '" + path + "' is a directory, not a file");
  }
  const io::StaleTemporaries stale = io::removeStaleTemporaries(path);
  for (const std::string& removed : stale.removed) {
    std::fprintf(stderr,
                 "raymap %s: removed '%s', a temporary file of an interrupted raymap whose "
                 "process is gone\n",
                 command_.c_str(), removed.c_str());
  }
  for (const std::string& problem : stale.errors) {
    std::fprintf(stderr, "raymap %s: warning: cannot remove a stale temporary file: %s\n",
                 command_.c_str(), problem.c_str());
  }

  Output output{path, option, io::temporaryPathFor(path), -1};
  // Registered before it exists, so that no moment has the file without its clean-up.
  output.signal_slot = platform::InterruptCleanup::add(command_, output.temp);
  // A file of this name can only be a leftover of an earlier process with our pid.
  ::unlink(output.temp.c_str());
  // Creating the temporary is the writability check. O_NOFOLLOW: the name is predictable, so a
  // symbolic link planted under it must not redirect the output.
  const int fd =
      ::open(output.temp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0666);
  if (fd < 0) {
    const std::string reason = platform::errnoText(errno);
    platform::InterruptCleanup::remove(output.signal_slot);
    return fail(ErrorCode::kIo, option + ": cannot write '" + path + "': " + reason);
  }
  ::close(fd);
  outputs_.push_back(output);
  return output.temp;
}

Expected<void, Error> StagedOutputs::commit() {
  // The renames are quick; a Ctrl-C among them waits, so the outputs are all there or none.
  const platform::InterruptCleanup::Deferral deferral;
  std::set<std::string> directories;
  for (std::size_t i = 0; i < outputs_.size(); ++i) {
    const Output& output = outputs_[i];
    if (std::rename(output.temp.c_str(), output.path.c_str()) != 0) {
      const std::string reason = platform::errnoText(errno);
      const std::string option = output.option;
      const std::string path = output.path;
      outputs_.erase(outputs_.begin(), outputs_.begin() + static_cast<std::ptrdiff_t>(i));
      removeAll();
      return fail(ErrorCode::kIo, option + ": cannot put '" + path + "' in place: " + reason);
    }
    platform::InterruptCleanup::remove(output.signal_slot);
    directories.insert(directoryOf(output.path));
  }
  outputs_.clear();
  // The files were flushed by their writers; this makes their new names durable too. Best
  // effort: the outputs are complete and in place whatever fsync of a directory says.
  for (const std::string& directory : directories) {
    const int fd = ::open(directory.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (fd >= 0) {
      static_cast<void>(::fsync(fd));
      ::close(fd);
    }
  }
  return {};
}

}  // namespace raymap::io
