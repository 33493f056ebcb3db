// SPDX-License-Identifier: BSD-3-Clause
// This process's UDP sockets as the kernel sees them: the cap on their receive buffers and the
// datagrams they dropped because a buffer was full (how large DDS samples are lost on a host).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace raymap::platform {

/// @brief net.core.rmem_max: the largest receive buffer an unprivileged SO_RCVBUF may ask for
/// (bytes), or 0 when it cannot be read. Start-up only (reads /proc).
std::uint64_t socketReceiveBufferCap() noexcept;

/// @brief Counts the datagrams the kernel dropped on this process's UDP sockets because their
/// receive buffer was full (the `drops` column of /proc/net/udp and udp6): each is a fragment of
/// a sample that then never completes. A DDS reader of best-effort data is not told of these.
///
/// Usage: `auto drops = UdpDrops::ofThisProcess();` once every socket exists (after the DDS
/// participant and its readers are created), then `drops.total()` once a report.
/// Thread-safety: one thread calls total(). @rt total() allocates: no (reads /proc into its own
/// buffer; two open/read/close per call), so it suits a 1 Hz diagnostics loop, not a hard
/// deadline.
class UdpDrops {
 public:
  /// @brief Finds this process's UDP sockets (from /proc/self/fd). Allocates.
  static UdpDrops ofThisProcess();

  /// @brief Sockets found (0 where /proc is not readable: total() then stays 0).
  std::size_t sockets() const noexcept { return inodes_.size(); }

  /// @brief Datagrams dropped so far by the sockets found, summed.
  std::uint64_t total() noexcept;

 private:
  std::vector<std::uint64_t> inodes_;  // sorted
  std::vector<char> buffer_;           // a chunk of /proc/net/udp, reused
};

}  // namespace raymap::platform
