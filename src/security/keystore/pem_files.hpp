// SPDX-License-Identifier: BSD-3-Clause
// Certificates and private keys to and from PEM text (PKCS#8 keys, unencrypted, as sros2).
#pragma once

#include <filesystem>
#include <string>
#include <string_view>

#include "raymap/error.hpp"

#include "src/security/openssl_handles.hpp"
#include "src/security/pem_reading.hpp"

namespace raymap::security {

/// @brief The PEM text of a certificate ("-----BEGIN CERTIFICATE-----").
Result<std::string> certificatePem(X509* certificate);
/// @brief The PKCS#8 PEM text of a private key ("-----BEGIN PRIVATE KEY-----"), unencrypted.
Result<std::string> privateKeyPem(EVP_PKEY* key);

/// A CA's certificate and private key.
struct CertificateAndKey {
  X509Ptr certificate;
  PkeyPtr key;
};

/// @brief Reads a certificate and its private key (WHAT: "the identity CA") and checks that
/// they belong together.
Result<CertificateAndKey> loadCertificateAndKey(const std::filesystem::path& certificate_file,
                                                const std::filesystem::path& key_file,
                                                const std::string& what);

/// A certificate's validity as ISO 8601 UTC texts ("2026-12-05T18:00:00"), as DDS Security's
/// permissions documents write them.
struct ValidityText {
  std::string not_before;
  std::string not_after;
};

/// @brief The validity of `certificate` as text.
Result<ValidityText> validityText(const X509* certificate);

}  // namespace raymap::security
