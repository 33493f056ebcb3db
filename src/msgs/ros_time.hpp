// SPDX-License-Identifier: BSD-3-Clause
// builtin_interfaces/Time and nanoseconds: the one conversion each way, for every header stamp
// raymap decodes, writes or prints.
#pragma once

#include <cstdint>

namespace raymap::msgs {

inline constexpr std::int64_t kNsPerSecond = 1'000'000'000;

/// @brief Nanoseconds since the epoch as builtin_interfaces/Time splits them: seconds rounded
/// down, so that 0 <= nanosec < 1e9 also before the epoch. The one split of every stamp raymap
/// writes (serializers, DDS samples) or prints.
struct RosTime {
  std::int64_t sec;
  std::uint32_t nanosec;
};
inline RosTime rosTimeOf(std::int64_t stamp_ns) noexcept {
  std::int64_t sec = stamp_ns / kNsPerSecond;
  std::int64_t nanosec = stamp_ns % kNsPerSecond;
  if (nanosec < 0) {
    nanosec += kNsPerSecond;
    sec -= 1;
  }
  return RosTime{sec, static_cast<std::uint32_t>(nanosec)};
}

/// @brief A ROS time (seconds and nanoseconds since the epoch) as nanoseconds since the epoch.
inline std::int64_t nanosecondsOf(std::int32_t sec, std::uint32_t nanosec) noexcept {
  return std::int64_t{sec} * kNsPerSecond + std::int64_t{nanosec};
}

}  // namespace raymap::msgs
