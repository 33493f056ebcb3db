// SPDX-License-Identifier: BSD-3-Clause
// raymapd as a child process of a test: started with extra environment variables, its standard
// error captured to a file, stopped by a signal with the time it took to exit.
#pragma once

#include <chrono>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <sys/types.h>

namespace raymap::test {

/// @brief How long a test lets a process take to exit after a signal. raymapd's threads stop
/// within a period (30 to 300 ms measured on the development VM), but a sanitizer build on a
/// busy 2-core CI runner is 5 to 15 times slower: a test checks that the exit is clean and
/// happens by itself, not how fast (the benchmarks record the stop time: docs/testing.md).
/// stop() returns as soon as the process has exited, so the margin costs nothing.
inline constexpr std::chrono::milliseconds kStopWait{20000};

/// @brief One running raymapd. Killed (SIGKILL) on destruction if still running.
class DaemonProcess {
 public:
  /// @brief fork + exec `binary args...` with `environment` added (NAME=value each).
  DaemonProcess(const std::string& binary, const std::vector<std::string>& args,
                const std::vector<std::string>& environment, const std::string& stderr_path);
  ~DaemonProcess();
  DaemonProcess(const DaemonProcess&) = delete;
  DaemonProcess& operator=(const DaemonProcess&) = delete;

  pid_t pid() const noexcept { return pid_; }
  /// @brief True while the process has not exited.
  bool running();
  /// @brief Sends `signal` and waits up to `timeout` for the exit.
  /// @return the exit status (or 128 + signal number) and how long the exit took; nullopt on
  /// timeout (the process is then killed).
  std::optional<std::pair<int, std::chrono::milliseconds>> stop(int signal,
                                                                std::chrono::milliseconds timeout);

 private:
  pid_t pid_ = -1;
  std::optional<int> status_;
};

/// @brief Runs `binary args...` to completion; returns its exit status and combined output.
std::pair<int, std::string> runToCompletion(const std::string& binary,
                                            const std::vector<std::string>& args);

}  // namespace raymap::test
