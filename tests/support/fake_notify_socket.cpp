// SPDX-License-Identifier: BSD-3-Clause
// FakeNotifySocket: a bound AF_UNIX datagram socket read with poll() and recvmsg().
#include "tests/support/fake_notify_socket.hpp"

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cstddef>
#include <cstring>
#include <stdexcept>
#include <string>
#include <utility>

#include <poll.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include "platform/errno_text.hpp"

namespace raymap::test {
namespace {

using Clock = std::chrono::steady_clock;

std::runtime_error systemError(const std::string& what) {
  return std::runtime_error("fake notify socket: " + what + ": " + platform::errnoText(errno));
}

}  // namespace

bool NotifyMessage::hasLine(std::string_view assignment) const {
  std::string_view rest = text;
  while (!rest.empty()) {
    const std::size_t end = rest.find('\n');
    if (rest.substr(0, end) == assignment) {
      return true;
    }
    if (end == std::string_view::npos) {
      break;
    }
    rest.remove_prefix(end + 1);
  }
  return false;
}

std::optional<std::string> NotifyMessage::value(std::string_view key) const {
  std::string_view rest = text;
  while (!rest.empty()) {
    const std::size_t end = rest.find('\n');
    const std::string_view line = rest.substr(0, end);
    if (line.size() > key.size() && line.substr(0, key.size()) == key && line[key.size()] == '=') {
      return std::string(line.substr(key.size() + 1));
    }
    if (end == std::string_view::npos) {
      break;
    }
    rest.remove_prefix(end + 1);
  }
  return std::nullopt;
}

FakeNotifySocket::FakeNotifySocket(Kind kind) {
  sockaddr_un address{};
  address.sun_family = AF_UNIX;
  socklen_t length = 0;
  if (kind == Kind::kPath) {
    dir_.emplace();
    path_ = dir_->file("notify");
    if (path_.size() >= sizeof(address.sun_path)) {
      throw std::runtime_error("fake notify socket: path too long: " + path_);
    }
    std::memcpy(address.sun_path, path_.data(), path_.size());
    length = static_cast<socklen_t>(offsetof(sockaddr_un, sun_path) + path_.size() + 1);
  } else {
    static std::atomic<int> counter{0};
    path_ = "@raymap-notify-" + std::to_string(getpid()) + "-" + std::to_string(counter++);
    std::memcpy(address.sun_path, path_.data(), path_.size());
    address.sun_path[0] = '\0';
    length = static_cast<socklen_t>(offsetof(sockaddr_un, sun_path) + path_.size());
  }
  fd_ = socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  if (fd_ < 0) {
    throw systemError("socket");
  }
  // the sockets API
  if (bind(fd_, reinterpret_cast<const sockaddr*>(&address), length) != 0) {
    const auto error = systemError("bind " + path_);
    ::close(fd_);
    throw error;
  }
  const int on = 1;
  (void)setsockopt(fd_, SOL_SOCKET, SO_PASSCRED, &on, sizeof(on));
}

FakeNotifySocket::~FakeNotifySocket() {
  if (fd_ >= 0) {
    ::close(fd_);
  }
}

std::optional<NotifyMessage> FakeNotifySocket::receive(std::chrono::milliseconds timeout) {
  const Clock::time_point deadline = Clock::now() + timeout;
  for (;;) {
    const auto left =
        std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now()).count();
    pollfd entry{fd_, POLLIN, 0};
    const int ready = poll(&entry, 1, static_cast<int>(std::max<long long>(left, 0)));
    if (ready < 0 && errno == EINTR) {
      continue;
    }
    if (ready < 0) {
      throw systemError("poll");
    }
    if (ready == 0) {
      return std::nullopt;
    }
    char data[4096];
    alignas(cmsghdr) char control[CMSG_SPACE(sizeof(ucred))];
    iovec part{data, sizeof(data)};
    msghdr header{};
    header.msg_iov = &part;
    header.msg_iovlen = 1;
    header.msg_control = control;
    header.msg_controllen = sizeof(control);
    const ssize_t received = recvmsg(fd_, &header, MSG_DONTWAIT | MSG_CMSG_CLOEXEC);
    if (received < 0 && (errno == EINTR || errno == EAGAIN)) {
      continue;
    }
    if (received < 0) {
      throw systemError("recvmsg");
    }
    NotifyMessage message;
    message.at = Clock::now();
    message.text.assign(data, static_cast<std::size_t>(received));
    for (cmsghdr* c = CMSG_FIRSTHDR(&header); c != nullptr; c = CMSG_NXTHDR(&header, c)) {
      if (c->cmsg_level == SOL_SOCKET && c->cmsg_type == SCM_CREDENTIALS) {
        ucred credentials{};
        std::memcpy(&credentials, CMSG_DATA(c), sizeof(credentials));
        message.sender_pid = credentials.pid;
      }
    }
    history_.push_back(message);
    return message;
  }
}

std::optional<NotifyMessage> FakeNotifySocket::waitFor(std::string_view line,
                                                       std::chrono::milliseconds timeout,
                                                       bool exact) {
  const Clock::time_point deadline = Clock::now() + timeout;
  for (;;) {
    const auto left =
        std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now());
    auto message = receive(std::max(left, std::chrono::milliseconds(0)));
    if (!message) {
      return std::nullopt;
    }
    if (exact ? message->hasLine(line) : message->text.find(line) != std::string::npos) {
      return message;
    }
  }
}

std::vector<NotifyMessage> FakeNotifySocket::collectFor(std::chrono::milliseconds duration) {
  std::vector<NotifyMessage> messages;
  const Clock::time_point deadline = Clock::now() + duration;
  for (;;) {
    const auto left =
        std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now());
    if (left.count() <= 0) {
      return messages;
    }
    if (auto message = receive(left)) {
      messages.push_back(std::move(*message));
    }
  }
}

Clock::duration FakeNotifySocket::maxGap(const std::vector<NotifyMessage>& messages,
                                         std::string_view line) {
  Clock::duration widest{0};
  std::optional<Clock::time_point> previous;
  for (const NotifyMessage& message : messages) {
    if (!message.hasLine(line)) {
      continue;
    }
    if (previous) {
      widest = std::max(widest, message.at - *previous);
    }
    previous = message.at;
  }
  return widest;
}

Clock::duration FakeNotifySocket::longestSilence(const std::vector<NotifyMessage>& messages,
                                                 std::string_view line, Clock::time_point from,
                                                 Clock::time_point to) {
  Clock::duration widest{0};
  Clock::time_point previous = from;
  for (const NotifyMessage& message : messages) {
    if (!message.hasLine(line) || message.at < from || message.at > to) {
      continue;
    }
    widest = std::max(widest, message.at - previous);
    previous = message.at;
  }
  return std::max(widest, to - previous);
}

}  // namespace raymap::test
