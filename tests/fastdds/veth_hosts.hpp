// SPDX-License-Identifier: BSD-3-Clause
// Two hosts on one Ethernet, made inside this machine for a test: two network namespaces joined
// by a virtual Ethernet pair, so DDS discovery runs over multicast as between a robot's
// computers, and no packet can leave the pair.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace raymap::test {

/// @brief Network namespaces "robot" and "planner" (named after this process, so tests may run
/// side by side), joined by a veth pair with multicast on: robot 10.213.0.1/24, planner
/// 10.213.0.2/24, each with its loopback up and its default route over the pair (as a robot's
/// computer has one; multicast needs a route). Deleted, with the pair, on destruction.
/// Needs root (CAP_NET_ADMIN and CAP_SYS_ADMIN) and `ip` (iproute2).
/// Thread-safety: one thread.
class VethHosts {
 public:
  enum class Host : std::uint8_t { kRobot, kPlanner };

  /// @return nullptr, with `why` saying what was missing, when this process cannot make them
  /// (not root, no `ip`, network namespaces not allowed in this container).
  static std::unique_ptr<VethHosts> create(std::string& why);
  ~VethHosts();
  VethHosts(const VethHosts&) = delete;
  VethHosts& operator=(const VethHosts&) = delete;

  /// @brief The command prefix that runs a program on `host`: `ip netns exec NAME` (the
  /// program's path and arguments follow).
  std::vector<std::string> launcher(Host host) const;
  /// @brief The name of `host`'s end of the pair (its only interface besides loopback).
  std::string interfaceOf(Host host) const;

 private:
  VethHosts() = default;
  std::string ip_;             // the ip program's path
  std::string namespaces_[2];  // robot, planner ("" until made)
  std::string interfaces_[2];  // each end's name once it is in its namespace
  std::string pair_;           // the pair's first end once made
};

}  // namespace raymap::test
