// SPDX-License-Identifier: BSD-3-Clause
// SystemdNotifier: the sd_notify protocol (READY, WATCHDOG, STATUS, STOPPING) without heap use.
#pragma once

#include <cstddef>
#include <cstdint>

#include <sys/socket.h>
#include <sys/un.h>

namespace raymap::platform {

/// @brief Sends service-manager notifications to $NOTIFY_SOCKET (Type=notify units) and knows
/// the watchdog interval from $WATCHDOG_USEC / $WATCHDOG_PID. Without NOTIFY_SOCKET (started from
/// a terminal) every call is a no-op, so the same binary runs anywhere.
///
/// Design: the constructor reads the environment, opens one AF_UNIX datagram socket (close-on-
/// exec) and stores the destination address (a path, or an abstract name written "@name"). Each
/// call then is one non-blocking sendmsg() of a gather list of constant strings and the caller's
/// text: no buffer, no heap, no lock. libsystemd's sd_notify() is not used on purpose: it builds
/// the message and address per call. Failures to send (manager gone, queue full) are dropped: a
/// missed watchdog ping is what the watchdog is there to notice.
/// Move-only owner of the socket. The environment is left as it is.
/// Thread-safety: after construction all const and notification calls may run concurrently
/// from any threads (datagrams are atomic). Construction and moves are not synchronised.
class SystemdNotifier {
 public:
  /// @brief Reads NOTIFY_SOCKET, WATCHDOG_USEC and WATCHDOG_PID (the watchdog counts only when
  /// WATCHDOG_PID is absent or this process's pid). Inactive when NOTIFY_SOCKET is unset, empty,
  /// not an absolute path or "@" name (e.g. a vsock address), too long, or no socket can be made.
  /// @rt start-up only (reads the environment, creates a socket); never fails.
  SystemdNotifier() noexcept;

  /// @brief Explicit destination, for tests and callers that do not use the environment.
  /// @param[in] socket_path "/path" or "@abstract"; nullptr or "" gives an inactive notifier.
  /// @param[in] watchdog_interval_ns WatchdogSec in ns, 0 = no watchdog.
  /// @rt start-up only; never fails.
  SystemdNotifier(const char* socket_path, std::int64_t watchdog_interval_ns) noexcept;

  SystemdNotifier(SystemdNotifier&& other) noexcept;
  SystemdNotifier& operator=(SystemdNotifier&& other) noexcept;
  SystemdNotifier(const SystemdNotifier&) = delete;
  SystemdNotifier& operator=(const SystemdNotifier&) = delete;
  ~SystemdNotifier();

  /// @brief True when a notify socket is set and open (running under a Type=notify unit).
  /// @rt wait-free; allocates: no; thread: any.
  bool active() const noexcept { return fd_ >= 0; }

  /// @brief WatchdogSec in nanoseconds (0 = no watchdog). Ping watchdog() at least twice per
  /// interval, from the loop whose progress it certifies, not from a timer thread.
  /// @rt wait-free; allocates: no; thread: any.
  std::int64_t watchdogIntervalNs() const noexcept { return watchdog_interval_ns_; }

  /// @brief Sends "READY=1\nSTATUS=<status>" (start-up complete). `status` may be nullptr (then
  /// only READY=1); text after a newline in it is dropped (it would be another assignment).
  /// @rt allocates: no; never blocks (MSG_DONTWAIT); syscalls: sendmsg; thread: any.
  void ready(const char* status) noexcept;

  /// @brief Sends "WATCHDOG=1" (keep-alive).
  /// @rt allocates: no; never blocks; syscalls: sendmsg; thread: any.
  void watchdog() noexcept;

  /// @brief Sends "STATUS=<text>" (the line systemctl status shows); text after a newline is
  /// dropped; nullptr sends nothing.
  /// @rt allocates: no; never blocks; syscalls: sendmsg; thread: any.
  void status(const char* text) noexcept;

  /// @brief Sends "STOPPING=1" (shutdown has begun).
  /// @rt allocates: no; never blocks; syscalls: sendmsg; thread: any.
  void stopping() noexcept;

 private:
  void open(const char* socket_path) noexcept;
  void send(const char* head, const char* text) noexcept;
  void close() noexcept;

  int fd_ = -1;
  std::int64_t watchdog_interval_ns_ = 0;
  sockaddr_un address_{};
  socklen_t address_length_ = 0;
};

}  // namespace raymap::platform
