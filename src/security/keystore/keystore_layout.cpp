// SPDX-License-Identifier: BSD-3-Clause
// Enclave names and the paths of a keystore's files.
#include "src/security/keystore/keystore_layout.hpp"

#include <string>
#include <system_error>

namespace raymap::security {

std::filesystem::path fromEnclaveTo(std::string_view name, std::string_view keystore_file) {
  // Relative to the keystore on both sides, as sros2's os.path.relpath: the governance of
  // enclave /a/b is "../../governance.p7s", its CA "../../../public/identity_ca.cert.pem".
  const std::filesystem::path folder = std::filesystem::path("enclaves") / name.substr(1);
  return std::filesystem::path(keystore_file).lexically_relative(folder);
}

Result<void> checkKeystore(const std::filesystem::path& keystore) {
  for (const char* file : {keystore_files::kIdentityCaCert, keystore_files::kIdentityCaKey,
                           keystore_files::kPermissionsCaCert, keystore_files::kPermissionsCaKey,
                           keystore_files::kGovernanceP7s}) {
    std::error_code error;
    if (!std::filesystem::is_regular_file(keystore / file, error)) {
      return fail(ErrorCode::kInvalidArgument,
                  keystore.string() + ": not a keystore: " + file +
                      " is missing (create one with `raymap security create-keystore`)");
    }
  }
  return {};
}

}  // namespace raymap::security
