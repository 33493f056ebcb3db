// SPDX-License-Identifier: BSD-3-Clause
// The decision every DDS program of raymap makes before it joins its domain: with security (the
// enclave's files, checked), without it because it was not asked for, or without it because the
// files are unusable and the strategy is Permissive (said loudly), or not at all (Enforce).
#pragma once

#include <cstdint>
#include <ctime>
#include <span>
#include <string>
#include <string_view>

#include "raymap/error.hpp"

#include "src/dds/entities.hpp"
#include "src/security/permissions_document.hpp"
#include "src/security/security_config.hpp"

namespace raymap::security {

/// @brief How a program joins its domain. A plain value.
struct SecurityOutcome {
  dds::SecurityFiles files;  ///< the enclave's files (empty: without security)
  /// Non-empty when the program must say loudly that it runs without the security it was asked
  /// for (Permissive), or when the identity or the grant expires within 30 days.
  std::string warning;
  /// One line for the log: "DDS Security: enclave /raymap/raymapd (subject CN=..., certificate
  /// valid until ...)" or "DDS Security: off".
  std::string summary;
  bool secure() const noexcept { return files.enabled(); }
};

/// @brief Applies `config`: off → no files; on → the enclave's files checked with
/// checkEnclave(domain, needs, now); unusable → an error (Enforce, the message prefixed with
/// where the setting came from) or no files and a warning (Permissive).
Result<SecurityOutcome> resolveSecurity(const SecurityConfig& config, std::uint32_t domain,
                                        std::span<const TopicNeed> needs, std::time_t now);

/// @brief For the command-line tools: security from ROS 2's variables (securityFromEnvironment
/// with `default_enclave`), a warning printed to stderr as "<program>: warning: ...", and a
/// participant on `domain` with it. Errors name the variable or file and the reason.
/// Start-up only.
Result<dds::Participant> openToolParticipant(std::uint32_t domain, std::string_view program,
                                             std::string_view default_enclave,
                                             const dds::DomainSettings& settings = {});

}  // namespace raymap::security
