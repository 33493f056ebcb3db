// SPDX-License-Identifier: BSD-3-Clause
// The writer of ROS 2 SROS2 keystores (`ros2 security`'s layout, names and signed documents):
// the CA, the signed governance, enclaves with their identity and signed permissions.
#pragma once

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "raymap/error.hpp"

namespace raymap::security {

/// The highest DDS domain id ROS 2 uses (ROS_DOMAIN_ID 0..232).
inline constexpr std::uint32_t kMaxKeystoreDomainId = 232;

/// DDS domains a governance or permissions document covers, inclusive; max >= min, max <= 232.
struct DomainRange {
  std::uint32_t min = 0;
  std::uint32_t max = 0;
};

/// @brief The domain ROS 2 tools default to: $ROS_DOMAIN_ID (0..232) when set, else 0 — as
/// sros2.
/// @return the one-domain range, or an error naming ROS_DOMAIN_ID and its bad value
Result<DomainRange> defaultDomainRange();

/// When a certificate (and the permissions granted to it) is valid.
struct Validity {
  std::chrono::system_clock::time_point not_before;
  std::chrono::system_clock::time_point not_after;
};

/// @brief From one day ago (so a peer whose clock lags still accepts it) until `days` days from
/// now: SROS2's convention (its certificates: now - 1 day .. now + 3650 days).
Validity validityForDays(int days);

/// What createKeystore makes.
struct KeystoreOptions {
  DomainRange domains;  ///< the governance's domains
  Validity ca_validity = validityForDays(3650);
  std::string common_name = "sros2CA";  ///< the CA's subject CN
};

/// What createEnclave and writePermissions make.
struct EnclaveOptions {
  DomainRange domains;                        ///< the permissions' domains
  Validity validity = validityForDays(3650);  ///< of a certificate made now (kept ones keep theirs)
};

/// What one enclave may publish and subscribe: DDS topic names ("rt/points", wildcards '*').
struct EnclaveGrant {
  std::string enclave;  ///< "/raymap/raymapd"
  std::vector<std::string> publish;
  std::vector<std::string> subscribe;
};

/// @brief Creates a keystore: public/ca.cert.pem, private/ca.key.pem (0600, in a 0700 folder),
/// the identity and permissions CA links to them, enclaves/governance.xml and its signature.
/// @param[in] keystore the folder; parent folders are created
/// @return an error naming the path when it already holds a keystore (public/ca.cert.pem or
/// enclaves/governance.p7s exist) or anything fails; nothing it made is left behind then
Result<void> createKeystore(const std::filesystem::path& keystore, const KeystoreOptions& options);

/// @brief Creates enclave `name` ("/a/b": enclaves/a/b/) in an existing keystore with the
/// allow-everything default permissions; an existing enclave keeps its key and certificate (as
/// sros2) but gets fresh permissions.
/// @return an error naming the keystore, the name or the file; on failure nothing changed
Result<void> createEnclave(const std::filesystem::path& keystore, std::string_view name,
                           const EnclaveOptions& options);

/// @brief Writes and signs permissions.xml/.p7s for grant.enclave (creating the enclave when it
/// has no key and certificate yet). ros_discovery_info is always granted (the rmw publish it).
/// @return an error naming the keystore, the name or the file; on failure nothing changed
Result<void> writePermissions(const std::filesystem::path& keystore, const EnclaveGrant& grant,
                              const EnclaveOptions& options);

/// @brief Reads a policy file (`enclaves: {NAME: {publish: [...], subscribe: [...]}}`, ROS 2
/// topic names) into grants with DDS topic names ("/points" -> "rt/points"), in file order.
/// @return an error naming the file, the line, the enclave and the entry or key
Result<std::vector<EnclaveGrant>> readPolicyFile(const std::filesystem::path& policy);

/// @brief Signs `document` with the keystore's permissions CA (S/MIME clear-signed, detached,
/// text/plain, SHA-256: what `openssl smime -sign -text` and sros2 write).
/// @return the .p7s text, or an error naming the CA file and the reason
Result<std::string> signWithPermissionsCa(const std::filesystem::path& keystore,
                                          std::string_view document);

/// @brief The enclaves of a keystore: every folder under enclaves/ holding key.pem, as "/a/b",
/// sorted (what `ros2 security list_enclaves` prints).
Result<std::vector<std::string>> listEnclaves(const std::filesystem::path& keystore);

}  // namespace raymap::security
