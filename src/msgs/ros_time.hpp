// SPDX-License-Identifier: BSD-3-Clause
// builtin_interfaces/Time as nanoseconds: the one conversion every decoded message's header stamp
// uses (the DDS samples' writer side is src/dds/ros_time.hpp).
#pragma once

#include <cstdint>

namespace raymap::msgs {

inline constexpr std::int64_t kNsPerSecond = 1'000'000'000;

/// @brief A ROS time (seconds and nanoseconds since the epoch) as nanoseconds since the epoch.
inline std::int64_t nanosecondsOf(std::int32_t sec, std::uint32_t nanosec) noexcept {
  return std::int64_t{sec} * kNsPerSecond + std::int64_t{nanosec};
}

}  // namespace raymap::msgs
