// SPDX-License-Identifier: BSD-3-Clause
// Enclave names and the paths of a keystore's files.
#include "src/security/keystore/keystore_layout.hpp"

#include <algorithm>
#include <string>
#include <system_error>

namespace raymap::security {
namespace {

constexpr std::size_t kMaxCommonNameLength = 64;  // X.509's ub-common-name

bool isNameCharacter(char c) {
  return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_';
}

std::string quoted(std::string_view name) {
  std::string text(1, '"');  // (not "\"" + string: a false -Wrestrict from GCC 12 at -O3)
  return text.append(name).append(1, '"');
}

}  // namespace

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
