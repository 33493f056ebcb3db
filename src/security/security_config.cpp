// SPDX-License-Identifier: BSD-3-Clause
// ROS 2's security environment variables and enclave names.
#include "src/security/security_config.hpp"

#include <algorithm>
#include <cstdlib>
#include <string>

namespace raymap::security {
namespace {

std::string_view environment(const char* name) {
  const char* value = std::getenv(name);  // NOLINT(concurrency-mt-unsafe): start-up, one thread
  return value == nullptr ? std::string_view() : std::string_view(value);
}

constexpr std::size_t kMaxCommonNameLength = 64;  // X.509's ub-common-name

bool isNameCharacter(char c) {
  return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_';
}

std::string quoted(std::string_view name) {
  std::string text(1, '"');  // (not "\"" + string: a false -Wrestrict from GCC 12 at -O3)
  return text.append(name).append(1, '"');
}

}  // namespace

Result<Strategy> parseStrategy(std::string_view text, std::string_view where) {
  if (text == "Enforce") {
    return Strategy::kEnforce;
  }
  if (text == "Permissive") {
    return Strategy::kPermissive;
  }
  return fail(ErrorCode::kInvalidArgument,
              std::string(where) + ": \"" + std::string(text) +
                  "\" is not a security strategy (Enforce or Permissive, as ROS 2 spells them)");
}

const char* strategyName(Strategy strategy) noexcept {
  return strategy == Strategy::kEnforce ? "Enforce" : "Permissive";
}

Result<void> checkEnclaveName(std::string_view name) {
  if (name.empty() || name.front() != '/') {
    return fail(ErrorCode::kInvalidArgument,
                "enclave name " + quoted(name) + ": must start with '/' (e.g. /raymap/raymapd)");
  }
  if (name.size() == 1) {
    return fail(ErrorCode::kInvalidArgument,
                "enclave name \"/\": the root is not an enclave; name one below it (e.g. /raymap)");
  }
  if (name.size() > kMaxCommonNameLength) {
    return fail(ErrorCode::kInvalidArgument,
                "enclave name " + quoted(name) + ": longer than " +
                    std::to_string(kMaxCommonNameLength) +
                    " characters, the most a certificate's common name holds");
  }
  std::size_t start = 1;
  while (start <= name.size()) {
    const std::size_t end = std::min(name.find('/', start), name.size());
    const std::string_view segment = name.substr(start, end - start);
    if (segment.empty()) {
      return fail(ErrorCode::kInvalidArgument,
                  "enclave name " + quoted(name) + ": has an empty segment ('//' or a final '/')");
    }
    if (!std::all_of(segment.begin(), segment.end(), isNameCharacter)) {
      return fail(ErrorCode::kInvalidArgument, "enclave name " + quoted(name) + ": segment \"" +
                                                   std::string(segment) +
                                                   "\" may hold only letters, digits and '_'");
    }
    if (segment.front() >= '0' && segment.front() <= '9') {
      // As ROS 2's namespace rules (rmw_validate_namespace), which sros2 applies.
      return fail(ErrorCode::kInvalidArgument, "enclave name " + quoted(name) + ": segment \"" +
                                                   std::string(segment) +
                                                   "\" must not start with a digit");
    }
    start = end + 1;
  }
  return {};
}

std::filesystem::path enclaveFolder(const std::filesystem::path& keystore, std::string_view name) {
  return keystore / "enclaves" / std::filesystem::path(name.substr(1));
}

Result<SecurityConfig> securityFromEnvironment(std::string_view default_enclave) {
  SecurityConfig config;
  config.source = "ROS_SECURITY_ENABLE";
  const std::string_view enable = environment("ROS_SECURITY_ENABLE");
  if (enable.empty() || enable == "false") {
    return config;
  }
  if (enable != "true") {
    return fail(ErrorCode::kInvalidArgument,
                "ROS_SECURITY_ENABLE=" + std::string(enable) +
                    ": must be true or false (ROS 2 turns security on only for \"true\")");
  }
  config.enabled = true;
  config.keystore = std::string(environment("ROS_SECURITY_KEYSTORE"));
  if (config.keystore.empty()) {
    return fail(ErrorCode::kInvalidArgument,
                "ROS_SECURITY_ENABLE=true but ROS_SECURITY_KEYSTORE is not set: it names the "
                "SROS2 keystore folder");
  }
  const std::string_view strategy = environment("ROS_SECURITY_STRATEGY");
  config.strategy = Strategy::kPermissive;
  if (!strategy.empty()) {
    auto parsed = parseStrategy(strategy, "ROS_SECURITY_STRATEGY");
    if (!parsed) {
      return Unexpected(std::move(parsed).error());
    }
    config.strategy = *parsed;
  }
  const std::string_view override_enclave = environment("ROS_SECURITY_ENCLAVE_OVERRIDE");
  config.enclave = std::string(override_enclave.empty() ? default_enclave : override_enclave);
  if (auto ok = checkEnclaveName(config.enclave); !ok) {
    return fail(ok.error().code,
                (override_enclave.empty() ? std::string("the default enclave")
                                          : std::string("ROS_SECURITY_ENCLAVE_OVERRIDE")) +
                    ": " + ok.error().message);
  }
  return config;
}

}  // namespace raymap::security
