// SPDX-License-Identifier: BSD-3-Clause
// Where SROS2 puts each file of a keystore and an enclave, and which enclave names are valid.
#pragma once

#include <filesystem>
#include <string>
#include <string_view>

#include "raymap/error.hpp"

#include "src/security/security_config.hpp"

namespace raymap::security {

/// The files of a keystore, relative to its folder (sros2's names).
namespace keystore_files {
inline constexpr const char* kCaCert = "public/ca.cert.pem";
inline constexpr const char* kCaKey = "private/ca.key.pem";
inline constexpr const char* kIdentityCaCert = "public/identity_ca.cert.pem";
inline constexpr const char* kIdentityCaKey = "private/identity_ca.key.pem";
inline constexpr const char* kPermissionsCaCert = "public/permissions_ca.cert.pem";
inline constexpr const char* kPermissionsCaKey = "private/permissions_ca.key.pem";
inline constexpr const char* kGovernanceXml = "enclaves/governance.xml";
inline constexpr const char* kGovernanceP7s = "enclaves/governance.p7s";
}  // namespace keystore_files

/// @brief The link target from an enclave folder to `keystore_file` (relative to the keystore),
/// e.g. "../../../public/identity_ca.cert.pem" for "/a/b". @pre a checked name
std::filesystem::path fromEnclaveTo(std::string_view name, std::string_view keystore_file);

/// @brief Checks that `keystore` holds a keystore sros2 would accept (both CA certificates and
/// keys, enclaves/governance.p7s).
/// @return an error naming the keystore and the missing file
Result<void> checkKeystore(const std::filesystem::path& keystore);

}  // namespace raymap::security
