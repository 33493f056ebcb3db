// SPDX-License-Identifier: BSD-3-Clause
// Writing a file so that readers see either the old file or the complete new one.
#pragma once

#include <cstddef>
#include <cstdio>
#include <span>
#include <string>

#include "raymap/error.hpp"

namespace raymap::io {

/// @brief Writes to a temporary file next to the destination (temporaryPathFor(): "<path>.raymap-
/// tmp-<pid>") and renames it over the destination on commit(), after flushing it to disk. If the
/// writer is destroyed without commit() (an error, an exception), the temporary file is removed
/// and the destination is untouched.
///
/// A destination that is itself a temporary name of this process (isOwnTemporaryPath(): a file
/// of a group of outputs that the caller renames into place together, tools/raymap/
/// staged_outputs.hpp) is written in place: commit() flushes it to disk and leaves the rename to
/// its owner, so there is one temporary name per output, never a temporary of a temporary.
/// Move-only; not thread-safe.
class AtomicFileWriter {
 public:
  /// @brief Creates the temporary file. Fails (naming the path and the reason) when the directory
  /// is missing or not writable.
  static Result<AtomicFileWriter> open(const std::string& path);

  AtomicFileWriter(AtomicFileWriter&& other) noexcept;
  AtomicFileWriter& operator=(AtomicFileWriter&& other) noexcept;
  AtomicFileWriter(const AtomicFileWriter&) = delete;
  AtomicFileWriter& operator=(const AtomicFileWriter&) = delete;
  ~AtomicFileWriter();

  /// @brief Appends bytes. Errors (disk full) are reported here or by commit().
  Expected<void, Error> write(std::span<const std::byte> bytes);
  Expected<void, Error> write(const std::string& text);
  /// @brief Overwrites bytes already written, starting `offset` bytes from the start of the file
  /// (e.g. a count in a header that is only known at the end); later writes still append.
  /// @pre offset + bytes.size() <= size(), else it fails with kInvalidArgument.
  Expected<void, Error> patch(std::size_t offset, std::span<const std::byte> bytes);
  Expected<void, Error> patch(std::size_t offset, const std::string& text);
  /// @brief Bytes written so far.
  std::size_t size() const noexcept { return written_; }
  /// @brief Flushes, fsyncs and renames onto the destination (in place: flushes and fsyncs).
  Expected<void, Error> commit();

  /// @brief The destination (for a staged temporary, the output it becomes).
  const std::string& path() const noexcept { return path_; }

 private:
  AtomicFileWriter(std::string path, std::string temp_path, std::FILE* file,
                   bool in_place) noexcept;
  void abandon() noexcept;

  std::string path_;
  std::string temp_path_;
  std::FILE* file_ = nullptr;
  std::size_t written_ = 0;
  bool in_place_ = false;  // temp_path_ is the destination's staged name: its owner renames it
};

}  // namespace raymap::io
