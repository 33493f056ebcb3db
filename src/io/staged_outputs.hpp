// SPDX-License-Identifier: BSD-3-Clause
// A program's output files: all of them appear, or none (docs/cli.md, "Output files").
#pragma once

#include <string>
#include <vector>

#include "raymap/error.hpp"

namespace raymap::io {

/// @brief The output files of one command, staged under temporary names
/// (io::temporaryPathFor(): "<path>.raymap-tmp-<pid>") and renamed into place together by
/// commit(). Whatever was not committed is removed on destruction, on SIGINT, SIGTERM and SIGHUP
/// (platform::InterruptCleanup), and, after a SIGKILL, by the next command that writes the same
/// output.
///
/// Declare the inputs first, then add() every output before the work starts: add() refuses an
/// output that is an input or another output, and creates the temporary file, so an unwritable
/// output fails before minutes are spent on the input. The io writers given a temporary path
/// write it in place (io::AtomicFileWriter). Not thread-safe.
class StagedOutputs {
 public:
  /// @param[in] command the subcommand, for messages ("populate").
  explicit StagedOutputs(std::string command);
  StagedOutputs(const StagedOutputs&) = delete;
  StagedOutputs& operator=(const StagedOutputs&) = delete;
  ~StagedOutputs();

  /// @brief Declares an input (a file, or a directory whose files are all inputs, like a bag).
  /// `what` names it in messages ("input", "--trajectory"). Empty paths and "-" are ignored.
  void input(const std::string& path, const std::string& what);

  /// @brief Stages output `path`, given with `option` ("--png"). Removes the temporaries of
  /// `path` that a killed run left (each named on standard error), then creates this run's.
  /// @return the temporary path to write the output to; kInvalidArgument when `path` is an
  /// input or another output (a usage error), kIo naming the option, the path and the reason
  /// when it cannot be written (a directory, a missing or unwritable directory).
  Result<std::string> add(const std::string& path, const std::string& option);

  /// @brief Renames every staged file onto its output, then flushes the directories to disk.
  /// A signal during the renames is acted on after them. @return kIo naming the output that
  /// could not be put in place (those not yet renamed are removed).
  Expected<void, Error> commit();

 private:
  struct Output {
    std::string path;
    std::string option;
    std::string temp;
    int signal_slot = -1;
  };
  struct Input {
    std::string path;
    std::string what;
  };
  void removeAll() noexcept;

  std::string command_;
  std::vector<Input> inputs_;
  std::vector<Output> outputs_;
};

}  // namespace raymap::io
