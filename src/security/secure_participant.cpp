// SPDX-License-Identifier: BSD-3-Clause
// Security on, off or refused, and the tools' participants.
#include "src/security/secure_participant.hpp"

#include <cstdio>

#include "src/security/enclave_check.hpp"

namespace raymap::security {
namespace {

constexpr std::time_t kExpiryWarningSeconds = 30 * 24 * 3600;

std::string expiryWarning(const EnclaveCheck& check, std::time_t now) {
  const std::time_t first = std::min(check.certificate_not_after, check.permissions_not_after);
  if (first - now > kExpiryWarningSeconds) {
    return {};
  }
  return std::string(check.certificate_not_after <= check.permissions_not_after
                         ? "the identity certificate"
                         : "the permissions") +
         " of " + check.subject + " expire on " + utcText(first) +
         ": renew them before then, or the robot's DDS traffic stops";
}

}  // namespace

Result<SecurityOutcome> resolveSecurity(const SecurityConfig& config, std::uint32_t domain,
                                        std::span<const TopicNeed> needs, std::time_t now) {
  SecurityOutcome outcome;
  if (!config.enabled) {
    outcome.summary = "DDS Security: off";
    return outcome;
  }
  const dds::SecurityFiles files = enclaveFilesIn(enclaveFolder(config));
  auto check = checkEnclave(files, domain, needs, now);
  if (!check) {
    if (config.strategy == Strategy::kEnforce) {
      return fail(check.error().code, config.source + " (Enforce): " + check.error().message);
    }
    outcome.warning = "running WITHOUT DDS Security (" + config.source +
                      ", strategy Permissive): " + check.error().message;
    outcome.summary = "DDS Security: off (Permissive, enclave unusable)";
    return outcome;
  }
  outcome.files = files;
  outcome.warning = expiryWarning(*check, now);
  outcome.summary = "DDS Security: " +
                    (config.enclave_dir.empty() ? "enclave " + config.enclave
                                                : "enclave files in " + config.enclave_dir) +
                    " (subject " + check->subject + ", certificate valid until " +
                    utcText(check->certificate_not_after) + ", permissions until " +
                    utcText(check->permissions_not_after) + ")";
  return outcome;
}

Result<dds::Participant> openToolParticipant(std::uint32_t domain, std::string_view program,
                                             std::string_view default_enclave,
                                             const dds::DomainSettings& settings) {
  auto config = securityFromEnvironment(default_enclave);
  if (!config) {
    return Unexpected(std::move(config).error());
  }
  auto outcome = resolveSecurity(*config, domain, {}, std::time(nullptr));
  if (!outcome) {
    return Unexpected(std::move(outcome).error());
  }
  if (!outcome->warning.empty()) {
    std::fprintf(stderr, "%.*s: warning: %s\n", static_cast<int>(program.size()), program.data(),
                 outcome->warning.c_str());
  }
  dds::DomainSettings secured = settings;
  secured.security = outcome->files;
  return dds::Participant::create(domain, secured);
}

}  // namespace raymap::security
