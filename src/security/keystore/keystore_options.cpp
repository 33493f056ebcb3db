// SPDX-License-Identifier: BSD-3-Clause
// The defaults of the keystore writer's options (ROS_DOMAIN_ID, SROS2's validity) and their
// checks.
#include "src/security/keystore/keystore_options.hpp"

#include <cerrno>
#include <cstdlib>
#include <string>

namespace raymap::security {

Result<DomainRange> defaultDomainRange() {
  const char* text = std::getenv("ROS_DOMAIN_ID");  // NOLINT(concurrency-mt-unsafe): read once
  if (text == nullptr || *text == '\0') {
    return DomainRange{0, 0};
  }
  char* end = nullptr;
  errno = 0;
  const long value = std::strtol(text, &end, 10);
  if (errno != 0 || end == text || *end != '\0' || value < 0 || value > kMaxKeystoreDomainId) {
    return fail(ErrorCode::kInvalidArgument,
                std::string("ROS_DOMAIN_ID=\"") + text + "\" is not a domain id (0.." +
                    std::to_string(kMaxKeystoreDomainId) +
                    "): set it right, or name the domains to cover explicitly");
  }
  const auto domain = static_cast<std::uint32_t>(value);
  return DomainRange{domain, domain};
}

Validity validityForDays(int days) {
  const auto now =
      std::chrono::time_point_cast<std::chrono::seconds>(std::chrono::system_clock::now());
  return Validity{now - std::chrono::days(1), now + std::chrono::days(days)};
}

Result<void> checkDomains(const DomainRange& domains) {
  if (domains.min > domains.max || domains.max > kMaxKeystoreDomainId) {
    return fail(ErrorCode::kInvalidArgument,
                "domains " + std::to_string(domains.min) + "-" + std::to_string(domains.max) +
                    ": not a range of domain ids (MIN-MAX with MIN <= MAX <= " +
                    std::to_string(kMaxKeystoreDomainId) + ")");
  }
  return {};
}

}  // namespace raymap::security
