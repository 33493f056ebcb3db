// SPDX-License-Identifier: BSD-3-Clause
// Nanoseconds -> builtin_interfaces/Time in the DDS samples raymapd writes (decoding: src/msgs).
#pragma once

#include <cstdint>

#include "builtin_interfaces.h"

#include "src/msgs/ros_time.hpp"

namespace raymap::dds {

inline void setRosTime(builtin_interfaces_msg_dds__Time_& time, std::int64_t stamp_ns) noexcept {
  std::int64_t sec = stamp_ns / msgs::kNsPerSecond;
  std::int64_t nanosec = stamp_ns % msgs::kNsPerSecond;
  if (nanosec < 0) {
    nanosec += msgs::kNsPerSecond;
    sec -= 1;
  }
  time.sec = static_cast<std::int32_t>(sec);
  time.nanosec = static_cast<std::uint32_t>(nanosec);
}

}  // namespace raymap::dds
