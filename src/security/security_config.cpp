// SPDX-License-Identifier: BSD-3-Clause
// ROS 2's security environment variables and enclave names.
#include "src/security/security_config.hpp"

#include <cstdlib>
#include <string>

namespace raymap::security {
namespace {

std::string_view environment(const char* name) {
  const char* value = std::getenv(name);
  return value == nullptr ? std::string_view() : std::string_view(value);
}

bool isNameCharacter(char c) {
  return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_';
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

Result<void> checkEnclaveName(std::string_view enclave, std::string_view where) {
  const auto bad = [&](const char* why) {
    return fail(ErrorCode::kInvalidArgument, std::string(where) + ": \"" + std::string(enclave) +
                                                 "\" is not an enclave name: " + why +
                                                 " (e.g. /raymap/raymapd)");
  };
  if (enclave.size() < 2 || enclave.front() != '/') {
    return bad("it must start with '/' and name at least one segment");
  }
  if (enclave.back() == '/') {
    return bad("it must not end with '/'");
  }
  char previous = '/';
  for (std::size_t i = 1; i < enclave.size(); ++i) {
    const char c = enclave[i];
    if (c == '/' && previous == '/') {
      return bad("it has an empty segment");
    }
    if (c != '/' && !isNameCharacter(c)) {
      return bad("segments are letters, digits and '_'");
    }
    previous = c;
  }
  return {};
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
  if (auto ok = checkEnclaveName(config.enclave, override_enclave.empty()
                                                     ? "the default enclave"
                                                     : "ROS_SECURITY_ENCLAVE_OVERRIDE");
      !ok) {
    return Unexpected(std::move(ok).error());
  }
  return config;
}

}  // namespace raymap::security
