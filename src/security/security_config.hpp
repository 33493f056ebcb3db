// SPDX-License-Identifier: BSD-3-Clause
// Whether a program joins its DDS domain with DDS Security, and with which SROS2 enclave: from
// ROS 2's environment variables (ROS_SECURITY_*) or from raymapd's `dds.security` section.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>

#include "raymap/error.hpp"

namespace raymap::security {

/// The enclave the raymap tools use unless ROS_SECURITY_ENCLAVE_OVERRIDE names another.
inline constexpr std::string_view kToolsEnclave = "/raymap/tools";
/// raymapd's enclave unless dds.security.enclave or ROS_SECURITY_ENCLAVE_OVERRIDE names another.
inline constexpr std::string_view kDaemonEnclave = "/raymap/raymapd";

/// What happens when security is asked for but the enclave's files are missing or invalid.
/// kEnforce: the program refuses to start. kPermissive: it starts without security and says so
/// loudly (ROS 2's meaning of ROS_SECURITY_STRATEGY=Permissive).
enum class Strategy : std::uint8_t { kEnforce, kPermissive };

/// @brief A program's security settings. A plain value; thread-safety: none needed.
struct SecurityConfig {
  bool enabled = false;
  /// The SROS2 keystore folder (public/, private/, enclaves/), as given (relative to the
  /// working directory when not absolute).
  std::string keystore;
  /// The enclave: a path like "/raymap/raymapd"; its files are in
  /// <keystore>/enclaves/raymap/raymapd.
  std::string enclave;
  /// A folder holding the enclave's files directly (cert.pem, key.pem, identity_ca.cert.pem,
  /// permissions_ca.cert.pem, governance.p7s, permissions.p7s), in place of keystore + enclave:
  /// how systemd hands them over (LoadCredential=, $CREDENTIALS_DIRECTORY). Empty: unused.
  std::string enclave_dir;
  Strategy strategy = Strategy::kEnforce;
  /// Where these settings came from, for messages: "ROS_SECURITY_ENABLE" or "file.yaml:12:
  /// dds.security".
  std::string source;
};

/// @brief "Enforce" or "Permissive" (ROS 2's spelling; case-sensitive as rcl reads it).
Result<Strategy> parseStrategy(std::string_view text, std::string_view where);

/// @brief The name ROS 2 gives a strategy.
const char* strategyName(Strategy strategy) noexcept;

/// @brief Security as ROS 2 nodes read it from the environment: on when ROS_SECURITY_ENABLE is
/// "true" (off when unset, empty or "false"); the keystore from ROS_SECURITY_KEYSTORE; the
/// enclave from ROS_SECURITY_ENCLAVE_OVERRIDE, else `default_enclave`; the strategy from
/// ROS_SECURITY_STRATEGY ("Enforce"; unset or empty: Permissive, as rcl).
/// @return the settings, or an error naming the variable and its bad value (another value of
/// ROS_SECURITY_ENABLE or ROS_SECURITY_STRATEGY, security on without ROS_SECURITY_KEYSTORE, an
/// enclave that is not an absolute name). Reads the environment: start-up only.
Result<SecurityConfig> securityFromEnvironment(std::string_view default_enclave);

/// The files of an enclave folder (enclaves/<name>/): SROS2's names, what Cyclone and Fast DDS
/// read.
namespace enclave_files {
inline constexpr const char* kKey = "key.pem";
inline constexpr const char* kCert = "cert.pem";
inline constexpr const char* kIdentityCaCert = "identity_ca.cert.pem";
inline constexpr const char* kPermissionsCaCert = "permissions_ca.cert.pem";
inline constexpr const char* kGovernanceP7s = "governance.p7s";
inline constexpr const char* kPermissionsXml = "permissions.xml";
inline constexpr const char* kPermissionsP7s = "permissions.p7s";
}  // namespace enclave_files

/// @brief <keystore>/enclaves/<name without its leading '/'> (SROS2's layout). @pre a name
/// that checkEnclaveName accepts
std::filesystem::path enclaveFolder(const std::filesystem::path& keystore, std::string_view name);

/// @brief Checks an enclave name: "/" then segments of [A-Za-z0-9_] separated by single '/'
/// ("/raymap/raymapd"), none starting with a digit (ROS 2's namespace rule, which sros2
/// applies), at most 64 characters (a certificate's CN); "/" alone, empty segments, "." and ".."
/// are refused.
/// @return an error quoting the name and saying what is wrong
Result<void> checkEnclaveName(std::string_view name);

}  // namespace raymap::security
