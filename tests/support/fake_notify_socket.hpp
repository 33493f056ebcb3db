// SPDX-License-Identifier: BSD-3-Clause
// FakeNotifySocket: plays systemd's side of $NOTIFY_SOCKET so tests can watch sd_notify traffic.
#pragma once

#include <chrono>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "tests/support/temp_dir.hpp"

namespace raymap::test {

/// One datagram received on the fake notify socket.
struct NotifyMessage {
  std::string text;                          ///< e.g. "READY=1\nSTATUS=mapping"
  std::chrono::steady_clock::time_point at;  ///< when receive() took it (steady clock)
  int sender_pid = 0;  ///< the sender's pid from SCM_CREDENTIALS (what NotifyAccess=main checks)

  /// @brief True when one line of the message is exactly `assignment` ("WATCHDOG=1").
  bool hasLine(std::string_view assignment) const;
  /// @brief The value of `key` ("STATUS" -> "mapping"), or nullopt when no line sets it.
  std::optional<std::string> value(std::string_view key) const;
};

/// @brief An AF_UNIX datagram socket bound at a unique path in its own temporary directory (or,
/// with Kind::kAbstract, at a unique abstract name written "@..."), with SO_PASSCRED on like
/// systemd's. Pass path() as NOTIFY_SOCKET to the program under test.
/// Every message received by any call is also appended to history().
/// Thread-safety: none; use from one test thread. Throws std::runtime_error when the socket
/// cannot be made.
class FakeNotifySocket {
 public:
  enum class Kind { kPath, kAbstract };

  explicit FakeNotifySocket(Kind kind = Kind::kPath);
  ~FakeNotifySocket();
  FakeNotifySocket(const FakeNotifySocket&) = delete;
  FakeNotifySocket& operator=(const FakeNotifySocket&) = delete;

  /// @brief The NOTIFY_SOCKET value: "/tmp/raymap-test-XXXXXX/notify" or "@raymap-notify-...".
  const std::string& path() const { return path_; }

  /// @brief Waits up to `timeout` for one datagram.
  std::optional<NotifyMessage> receive(std::chrono::milliseconds timeout);

  /// @brief Receives until a message has a line equal to `line` (e.g. "READY=1") or one that
  /// contains `line` as a substring when `exact` is false; other messages are only recorded.
  /// @return that message, or nullopt when `timeout` passes first.
  std::optional<NotifyMessage> waitFor(std::string_view line, std::chrono::milliseconds timeout,
                                       bool exact = true);

  /// @brief Receives everything that arrives during `duration` (for watchdog gap checks).
  std::vector<NotifyMessage> collectFor(std::chrono::milliseconds duration);

  /// @brief Every message received so far, oldest first.
  const std::vector<NotifyMessage>& history() const { return history_; }

  /// @brief Largest gap between consecutive messages that have `line` (e.g. "WATCHDOG=1") in
  /// `messages`; zero when fewer than two have it.
  static std::chrono::steady_clock::duration maxGap(const std::vector<NotifyMessage>& messages,
                                                    std::string_view line);

  /// @brief The longest stretch of [from, to] without a message of `messages` that has `line`,
  /// the two ends included: what systemd's watchdog would have seen over that interval (no such
  /// message at all gives to - from, where maxGap() gives zero).
  static std::chrono::steady_clock::duration longestSilence(
      const std::vector<NotifyMessage>& messages, std::string_view line,
      std::chrono::steady_clock::time_point from, std::chrono::steady_clock::time_point to);

 private:
  std::optional<TempDir> dir_;
  std::string path_;
  int fd_ = -1;
  std::vector<NotifyMessage> history_;
};

}  // namespace raymap::test
