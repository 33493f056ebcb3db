// SPDX-License-Identifier: BSD-3-Clause
// Nanoseconds -> builtin_interfaces/Time in the DDS samples raymapd writes (decoding: src/msgs).
#pragma once

#include <cstdint>

#include "builtin_interfaces.h"

#include "src/msgs/ros_time.hpp"

namespace raymap::dds {

inline void setRosTime(builtin_interfaces_msg_dds__Time_& time, std::int64_t stamp_ns) noexcept {
  const msgs::RosTime t = msgs::rosTimeOf(stamp_ns);
  time.sec = static_cast<std::int32_t>(t.sec);
  time.nanosec = t.nanosec;
}

}  // namespace raymap::dds
