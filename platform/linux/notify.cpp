// SPDX-License-Identifier: BSD-3-Clause
// SystemdNotifier on Linux: one AF_UNIX datagram socket, one sendmsg() per notification.
#include "platform/notify.hpp"

#include <cerrno>
#include <cstddef>
#include <cstdlib>
#include <cstring>
#include <utility>

#include <sys/uio.h>
#include <unistd.h>

namespace raymap::platform {
namespace {

/// Parses a decimal unsigned number that fills the whole string; false otherwise.
bool parseUnsigned(const char* text, unsigned long long* value) noexcept {
  if (text == nullptr || *text < '0' || *text > '9') {
    return false;
  }
  errno = 0;
  char* end = nullptr;
  *value = std::strtoull(text, &end, 10);
  return errno == 0 && end != nullptr && *end == '\0';
}

/// The watchdog interval systemd announced to this process, in ns (0 = none). Same rules as
/// sd_watchdog_enabled(): WATCHDOG_PID, when set, must be our pid; WATCHDOG_USEC must be > 0.
std::int64_t watchdogFromEnvironment() noexcept {
  unsigned long long usec = 0;
  // NOLINTNEXTLINE(concurrency-mt-unsafe): read once, when raymapd starts, before its threads
  if (!parseUnsigned(std::getenv("WATCHDOG_USEC"), &usec) || usec == 0) {
    return 0;
  }
  // NOLINTNEXTLINE(concurrency-mt-unsafe): read once, when raymapd starts, before its threads
  const char* pid_text = std::getenv("WATCHDOG_PID");
  if (pid_text != nullptr) {
    unsigned long long pid = 0;
    if (!parseUnsigned(pid_text, &pid) || pid != static_cast<unsigned long long>(getpid())) {
      return 0;
    }
  }
  constexpr unsigned long long kMaxUsec = 9'000'000'000'000'000ull / 1000ull;  // fits int64 ns
  return static_cast<std::int64_t>(usec > kMaxUsec ? kMaxUsec : usec) * 1000;
}

/// Length of the first line of `text` (the rest would be read as further assignments).
std::size_t firstLineLength(const char* text) noexcept { return std::strcspn(text, "\n"); }

}  // namespace

SystemdNotifier::SystemdNotifier() noexcept : watchdog_interval_ns_(watchdogFromEnvironment()) {
  // NOLINTNEXTLINE(concurrency-mt-unsafe): read once, when raymapd starts, before its threads
  open(std::getenv("NOTIFY_SOCKET"));
}

SystemdNotifier::SystemdNotifier(const char* socket_path,
                                 std::int64_t watchdog_interval_ns) noexcept
    : watchdog_interval_ns_(watchdog_interval_ns > 0 ? watchdog_interval_ns : 0) {
  open(socket_path);
}

SystemdNotifier::SystemdNotifier(SystemdNotifier&& other) noexcept
    : fd_(std::exchange(other.fd_, -1)),
      watchdog_interval_ns_(std::exchange(other.watchdog_interval_ns_, 0)),
      address_(other.address_),
      address_length_(std::exchange(other.address_length_, 0)) {}

SystemdNotifier& SystemdNotifier::operator=(SystemdNotifier&& other) noexcept {
  if (this != &other) {
    close();
    fd_ = std::exchange(other.fd_, -1);
    watchdog_interval_ns_ = std::exchange(other.watchdog_interval_ns_, 0);
    address_ = other.address_;
    address_length_ = std::exchange(other.address_length_, 0);
  }
  return *this;
}

SystemdNotifier::~SystemdNotifier() { close(); }

void SystemdNotifier::open(const char* socket_path) noexcept {
  if (socket_path == nullptr || (socket_path[0] != '/' && socket_path[0] != '@')) {
    return;  // unset, empty, or a kind of address we do not speak (vsock:...)
  }
  const std::size_t length = std::strlen(socket_path);
  if (length < 2 || length >= sizeof(address_.sun_path)) {
    return;
  }
  address_ = sockaddr_un{};
  address_.sun_family = AF_UNIX;
  std::memcpy(address_.sun_path, socket_path, length);
  if (socket_path[0] == '@') {
    address_.sun_path[0] = '\0';  // Linux abstract namespace: the length delimits the name
    address_length_ = static_cast<socklen_t>(offsetof(sockaddr_un, sun_path) + length);
  } else {
    address_length_ = static_cast<socklen_t>(offsetof(sockaddr_un, sun_path) + length + 1);
  }
  fd_ = socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  if (fd_ < 0) {
    address_length_ = 0;
  }
}

void SystemdNotifier::close() noexcept {
  if (fd_ >= 0) {
    (void)::close(fd_);
    fd_ = -1;
  }
}

void SystemdNotifier::send(const char* head, const char* text) noexcept {
  if (fd_ < 0) {
    return;
  }
  // iovec's base is non-const in the C API; sendmsg only reads it.
  iovec parts[2] = {};
  // NOLINTNEXTLINE(cppcoreguidelines-pro-type-const-cast): sendmsg only reads it
  parts[0].iov_base = const_cast<char*>(head);
  parts[0].iov_len = std::strlen(head);
  std::size_t count = 1;
  if (text != nullptr) {
    // NOLINTNEXTLINE(cppcoreguidelines-pro-type-const-cast): sendmsg only reads it
    parts[1].iov_base = const_cast<char*>(text);
    parts[1].iov_len = firstLineLength(text);
    count = 2;
  }
  msghdr message{};
  message.msg_name = &address_;
  message.msg_namelen = address_length_;
  message.msg_iov = parts;
  message.msg_iovlen = count;
  // MSG_DONTWAIT: a full receive queue must not stall a real-time thread; MSG_NOSIGNAL: no
  // SIGPIPE. The result is ignored on purpose (see the class comment).
  ssize_t sent = 0;
  do {
    sent = sendmsg(fd_, &message, MSG_DONTWAIT | MSG_NOSIGNAL);
  } while (sent < 0 && errno == EINTR);
}

void SystemdNotifier::ready(const char* status) noexcept {
  if (status == nullptr) {
    send("READY=1", nullptr);
  } else {
    send("READY=1\nSTATUS=", status);
  }
}

void SystemdNotifier::watchdog() noexcept { send("WATCHDOG=1", nullptr); }

void SystemdNotifier::status(const char* text) noexcept {
  if (text != nullptr) {
    send("STATUS=", text);
  }
}

void SystemdNotifier::stopping() noexcept { send("STOPPING=1", nullptr); }

}  // namespace raymap::platform
