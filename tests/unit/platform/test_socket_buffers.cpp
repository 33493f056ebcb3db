// SPDX-License-Identifier: BSD-3-Clause
// UdpDrops: datagrams the kernel dropped on this process's sockets for want of buffer space.
#include <array>
#include <cstdint>

#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include "platform/socket_buffers.hpp"

namespace raymap::platform {
namespace {

/// A UDP socket on 127.0.0.1 with a tiny receive buffer, and a sender to it.
class LoopbackPair {
 public:
  LoopbackPair() {
    receiver_ = ::socket(AF_INET, SOCK_DGRAM, 0);
    sender_ = ::socket(AF_INET, SOCK_DGRAM, 0);
    const int tiny = 1;  // the kernel's minimum
    ::setsockopt(receiver_, SOL_SOCKET, SO_RCVBUF, &tiny, sizeof(tiny));
    address_.sin_family = AF_INET;
    address_.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    address_.sin_port = 0;
    ::bind(receiver_, reinterpret_cast<const sockaddr*>(&address_), sizeof(address_));
    socklen_t length = sizeof(address_);
    ::getsockname(receiver_, reinterpret_cast<sockaddr*>(&address_), &length);
  }
  ~LoopbackPair() {
    ::close(receiver_);
    ::close(sender_);
  }
  LoopbackPair(const LoopbackPair&) = delete;
  LoopbackPair& operator=(const LoopbackPair&) = delete;

  /// Sends `n` datagrams of 8 KiB that nobody reads (loopback delivers at once: the buffer fills
  /// after a few and the kernel drops the rest).
  void flood(int n) const {
    static const std::array<char, 8192> payload{};
    for (int i = 0; i < n; ++i) {
      ::sendto(sender_, payload.data(), payload.size(), 0,
               reinterpret_cast<const sockaddr*>(&address_), sizeof(address_));
    }
  }

 private:
  int receiver_ = -1;
  int sender_ = -1;
  sockaddr_in address_{};
};

TEST(UdpDrops, CountsTheDatagramsAFullReceiveBufferDropped) {
  LoopbackPair pair;
  UdpDrops drops = UdpDrops::ofThisProcess();
  if (drops.sockets() == 0) {
    GTEST_SKIP() << "/proc/self/fd is not readable here";
  }
  const std::uint64_t before = drops.total();
  pair.flood(64);
  const std::uint64_t after = drops.total();
  EXPECT_GT(after, before) << "64 datagrams of 8 KiB into a buffer of a few KiB";
  EXPECT_LE(after - before, 64u);
  pair.flood(64);
  EXPECT_GT(drops.total(), after) << "counted again on the next call";
}

TEST(UdpDrops, SocketsOpenedAfterwardsAreNotCounted) {
  UdpDrops drops = UdpDrops::ofThisProcess();
  const std::uint64_t before = drops.total();
  LoopbackPair later;
  later.flood(64);
  EXPECT_EQ(drops.total(), before);
}

TEST(SocketReceiveBufferCap, IsReadFromTheKernel) {
  // Linux's minimum for net.core.rmem_max is a few KiB; 0 only where /proc is not mounted.
  const std::uint64_t cap = socketReceiveBufferCap();
  if (cap == 0) {
    GTEST_SKIP() << "/proc/sys/net/core/rmem_max is not readable here";
  }
  EXPECT_GE(cap, 4096u);
}

}  // namespace
}  // namespace raymap::platform
