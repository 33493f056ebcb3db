// SPDX-License-Identifier: BSD-3-Clause
// Reading the files of a keystore: whole files, PEM certificates and unencrypted PEM private keys
// (never a passphrase prompt). Shared by the keystore writer and the enclave checks.
#pragma once

#include <filesystem>
#include <string>
#include <string_view>

#include "raymap/error.hpp"

#include "src/security/openssl_handles.hpp"

namespace raymap::security {

/// @brief The whole content of `file`; the error reads "FILE: cannot read WHAT: REASON".
Result<std::string> readWholeFile(const std::filesystem::path& file, std::string_view what);

/// @brief Reads a PEM certificate file; errors read "FILE: cannot read WHAT: REASON".
Result<X509Ptr> loadCertificate(const std::filesystem::path& file, std::string_view what);

/// @brief Reads an unencrypted PEM private key file (never asks for a passphrase).
Result<PkeyPtr> loadPrivateKey(const std::filesystem::path& file, std::string_view what);

/// @brief An error whose message is `what` followed by OpenSSL's queued errors (cleared).
Unexpected<Error> opensslFailure(const std::string& what);

}  // namespace raymap::security
