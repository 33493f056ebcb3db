// SPDX-License-Identifier: BSD-3-Clause
// PKCS7_sign + SMIME_write_PKCS7 with PKCS7_DETACHED | PKCS7_TEXT (what sros2 calls).
#include "src/security/keystore/smime_signer.hpp"

namespace raymap::security {

Result<std::string> signSmime(X509* signer_certificate, EVP_PKEY* signer_key,
                              std::string_view document) {
  constexpr int kFlags = PKCS7_DETACHED | PKCS7_TEXT;
  auto failed = [](const char* step) {
    const std::string reason = takeOpensslErrors();
    return fail(ErrorCode::kInvalidArgument,
                std::string(step) + (reason.empty() ? "" : ": " + reason));
  };
  // PKCS7_sign reads the document to digest it; SMIME_write_PKCS7 needs it again for the clear
  // part, so each gets its own BIO.
  BioPtr to_sign = memoryBio(document);
  if (!to_sign) {
    return failed("cannot sign the document");
  }
  Pkcs7Ptr signature(PKCS7_sign(signer_certificate, signer_key, nullptr, to_sign.get(), kFlags));
  if (!signature) {
    return failed("cannot sign the document");
  }
  BioPtr clear_text = memoryBio(document);
  BioPtr out(BIO_new(BIO_s_mem()));
  if (!clear_text || !out ||
      SMIME_write_PKCS7(out.get(), signature.get(), clear_text.get(), kFlags) != 1) {
    return failed("cannot write the signed document as S/MIME");
  }
  return bioText(out.get());
}

}  // namespace raymap::security
