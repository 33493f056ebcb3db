// SPDX-License-Identifier: BSD-3-Clause
// Keys and X.509 certificates as sros2 makes them: EC prime256v1 keys, SHA-256 signatures, a
// self-signed CA (CA:TRUE, pathlen 1, critical) and enclave identities (CA:FALSE) it signs.
#pragma once

#include <string_view>

#include "raymap/error.hpp"

#include "src/security/keystore/keystore_writer.hpp"
#include "src/security/openssl_handles.hpp"

namespace raymap::security {

/// A new private key and the certificate of its public key.
struct KeyAndCertificate {
  PkeyPtr key;
  X509Ptr certificate;
};

/// @brief A new EC key on prime256v1 (P-256), the curve DDS Security 9.3.1 calls for.
Result<PkeyPtr> makeP256Key();

/// @brief A new CA: key and self-signed certificate with subject CN=`common_name`.
/// @return an error naming the common name and OpenSSL's reason
Result<KeyAndCertificate> makeCaCertificate(std::string_view common_name, const Validity& validity);

/// @brief A new identity: key and certificate with subject CN=`name`, issued and signed by the
/// CA (`ca_certificate`'s subject as issuer).
Result<KeyAndCertificate> makeIdentityCertificate(std::string_view name, const Validity& validity,
                                                  X509* ca_certificate, EVP_PKEY* ca_key);

}  // namespace raymap::security
