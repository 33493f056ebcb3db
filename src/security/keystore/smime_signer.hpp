// SPDX-License-Identifier: BSD-3-Clause
// S/MIME clear-signed documents (.p7s), the form DDS Security wants its governance and
// permissions in.
#pragma once

#include <string>
#include <string_view>

#include "raymap/error.hpp"

#include "src/security/openssl_handles.hpp"

namespace raymap::security {

/// @brief Signs `document` as `openssl smime -sign -text` does: a detached PKCS#7 signature
/// (SHA-256, the signer's certificate included) over the text/plain MIME part, written as
/// multipart/signed S/MIME with the document in clear.
/// @return the .p7s text, or an error with OpenSSL's reason
Result<std::string> signSmime(X509* signer_certificate, EVP_PKEY* signer_key,
                              std::string_view document);

}  // namespace raymap::security
