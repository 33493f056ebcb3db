// SPDX-License-Identifier: BSD-3-Clause
// What `raymap topics` and `raymap echo` share: the domain id default, the text of times and
// printable wire strings.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>

#include "raymap/error.hpp"

namespace raymap::cli {

/// The highest ROS_DOMAIN_ID (ROS 2's documented range is 0..232: Cyclone's port mapping).
inline constexpr int kMaxDomainId = 232;

/// @brief The domain to join: `option` when given (>= 0), else $ROS_DOMAIN_ID when set and not
/// empty, else 0 (as ROS 2 does).
/// @return the id, or an error naming ROS_DOMAIN_ID and its bad value
Result<std::uint32_t> domainFromOptionOrEnvironment(int option);

/// @brief Seconds as the messages print them: "1.5 s", "5 s".
std::string secondsText(double seconds);

/// @brief A ROS stamp (nanoseconds since the epoch) as "sec.nanosec" with nine digits, e.g.
/// "1700000000.250000000" (floor division: a stamp before the epoch reads "-1.999999999").
std::string stampText(std::int64_t stamp_ns);

/// @brief `text` made safe to print: invalid UTF-8 bytes become U+FFFD, and (for terminals)
/// control characters become '?'. Strings from the wire are not trusted to be either.
std::string printableText(std::string_view text, bool replace_controls);

}  // namespace raymap::cli
