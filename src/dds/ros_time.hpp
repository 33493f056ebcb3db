// SPDX-License-Identifier: BSD-3-Clause
// builtin_interfaces/Time <-> nanoseconds, the one conversion every message's header stamp uses.
#pragma once

#include <cstdint>

#include "builtin_interfaces.h"

namespace raymap::dds {

inline constexpr std::int64_t kNsPerSecond = 1'000'000'000;

/// @brief Nanoseconds since the epoch as a ROS Time: floor division, so that a stamp before the
/// epoch still has 0 <= nanosec < 1e9. @rt allocates: no.
inline void setRosTime(builtin_interfaces_msg_dds__Time_& time, std::int64_t stamp_ns) noexcept {
  std::int64_t sec = stamp_ns / kNsPerSecond;
  std::int64_t nanosec = stamp_ns % kNsPerSecond;
  if (nanosec < 0) {
    nanosec += kNsPerSecond;
    sec -= 1;
  }
  time.sec = static_cast<std::int32_t>(sec);
  time.nanosec = static_cast<std::uint32_t>(nanosec);
}

/// @brief A ROS Time (sec, nanosec) as nanoseconds since the epoch. @rt allocates: no.
inline std::int64_t nanosecondsOf(std::int32_t sec, std::uint32_t nanosec) noexcept {
  return std::int64_t{sec} * kNsPerSecond + std::int64_t{nanosec};
}

}  // namespace raymap::dds
