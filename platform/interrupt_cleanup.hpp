// SPDX-License-Identifier: BSD-3-Clause
// Temporary output files removed when SIGINT, SIGTERM or SIGHUP ends the command (Ctrl-C, a
// service manager's stop, a closed terminal).
#pragma once

#include <string>

namespace raymap::platform {

/// @brief A process-wide list of temporary files that a handler of SIGINT, SIGTERM and SIGHUP
/// removes before the process ends by that signal (so the shell sees the usual 128 + N), with a
/// message on standard error. The handlers are installed with the first file; a signal the
/// process ignores (nohup's SIGHUP) stays ignored. Commands that take those signals
/// synchronously (record, replay, echo: platform/signals.hpp blocks them) never run the
/// handler: their loop stops and the command's own clean-up removes the files.
///
/// The handler only reads fixed static storage and calls unlink(), write() and raise()
/// (async-signal-safe). Thread-safe. A SIGKILL cannot be caught: what it leaves, a later run
/// that writes the same output removes (io::removeStaleTemporaries()).
class InterruptCleanup {
 public:
  /// @brief Registers `path` for removal; `command` names the command in the message.
  /// @return the slot to pass to remove(), or -1 when the list is full or the path too long (the
  /// file is then left to a later run's stale clean-up).
  static int add(const std::string& command, const std::string& path) noexcept;
  /// @brief Forgets a slot (the file was renamed into place or removed). -1 is ignored.
  static void remove(int slot) noexcept;

  /// @brief While one lives, a signal waits: it is acted on when the last one ends, by the
  /// default action (the renames of a group of outputs are never cut in half).
  class Deferral {
   public:
    Deferral() noexcept;
    ~Deferral();
    Deferral(const Deferral&) = delete;
    Deferral& operator=(const Deferral&) = delete;
  };
};

}  // namespace raymap::platform
