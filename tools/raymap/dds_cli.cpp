// SPDX-License-Identifier: BSD-3-Clause
// Domain id default, time texts and printable wire strings of the DDS commands.
#include "tools/raymap/dds_cli.hpp"

#include <cerrno>
#include <cinttypes>
#include <cstdio>
#include <cstdlib>

#include "src/msgs/ros_time.hpp"

namespace raymap::cli {

Result<std::uint32_t> domainFromOptionOrEnvironment(int option) {
  if (option >= 0) {
    return static_cast<std::uint32_t>(option);
  }
  const char* text = std::getenv("ROS_DOMAIN_ID");
  if (text == nullptr || *text == '\0') {
    return std::uint32_t{0};
  }
  char* end = nullptr;
  errno = 0;
  const long value = std::strtol(text, &end, 10);
  if (errno != 0 || end == text || *end != '\0' || value < 0 || value > kMaxDomainId) {
    return fail(ErrorCode::kInvalidArgument,
                std::string("ROS_DOMAIN_ID=\"") + text + "\" is not a domain id (0.." +
                    std::to_string(kMaxDomainId) + "); set it right or pass --domain");
  }
  return static_cast<std::uint32_t>(value);
}

std::string secondsText(double seconds) {
  char buffer[64];
  std::snprintf(buffer, sizeof(buffer), "%g s", seconds);
  return buffer;
}

std::string stampText(std::int64_t stamp_ns) {
  const msgs::RosTime t = msgs::rosTimeOf(stamp_ns);
  char buffer[64];
  std::snprintf(buffer, sizeof(buffer), "%" PRId64 ".%09" PRIu32, t.sec, t.nanosec);
  return buffer;
}

std::string printableText(std::string_view text, bool replace_controls) {
  static constexpr const char* kReplacement = "\xEF\xBF\xBD";  // U+FFFD in UTF-8
  std::string out;
  out.reserve(text.size());
  std::size_t i = 0;
  while (i < text.size()) {
    const auto byte = static_cast<unsigned char>(text[i]);
    if (byte < 0x80) {
      out += (replace_controls && (byte < 0x20 || byte == 0x7F)) ? '?' : text[i];
      ++i;
      continue;
    }
    // The length of the sequence and the smallest code point it may encode (no overlong forms).
    std::size_t length = 0;
    std::uint32_t code = 0;
    std::uint32_t min_code = 0;
    if ((byte & 0xE0) == 0xC0) {
      length = 2;
      code = byte & 0x1FU;
      min_code = 0x80;
    } else if ((byte & 0xF0) == 0xE0) {
      length = 3;
      code = byte & 0x0FU;
      min_code = 0x800;
    } else if ((byte & 0xF8) == 0xF0) {
      length = 4;
      code = byte & 0x07U;
      min_code = 0x10000;
    }
    bool valid = length > 0 && i + length <= text.size();
    for (std::size_t k = 1; valid && k < length; ++k) {
      const auto next = static_cast<unsigned char>(text[i + k]);
      valid = (next & 0xC0) == 0x80;
      code = (code << 6) | (next & 0x3FU);
    }
    valid = valid && code >= min_code && code <= 0x10FFFF && (code < 0xD800 || code > 0xDFFF);
    if (valid) {
      out.append(text.substr(i, length));
      i += length;
    } else {
      out += kReplacement;
      ++i;
    }
  }
  return out;
}

}  // namespace raymap::cli
