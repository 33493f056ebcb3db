// SPDX-License-Identifier: BSD-3-Clause
// PEM reading and writing through OpenSSL memory BIOs, certificate times as ISO 8601 text.
#include "src/security/keystore/pem_files.hpp"

#include <ctime>

#include <openssl/pem.h>

#include "src/security/pem_reading.hpp"

namespace raymap::security {
namespace {

Result<std::string> isoText(const ASN1_TIME* time, const char* which) {
  std::tm tm{};
  if (time == nullptr || ASN1_TIME_to_tm(time, &tm) != 1) {
    return opensslFailure(std::string("the certificate's ") + which + " time does not decode");
  }
  char buffer[32];
  std::strftime(buffer, sizeof buffer, "%Y-%m-%dT%H:%M:%S", &tm);
  return std::string(buffer);
}

}  // namespace

Result<std::string> certificatePem(X509* certificate) {
  BioPtr out(BIO_new(BIO_s_mem()));
  if (!out || PEM_write_bio_X509(out.get(), certificate) != 1) {
    return opensslFailure("cannot write the certificate as PEM");
  }
  return bioText(out.get());
}

Result<std::string> privateKeyPem(EVP_PKEY* key) {
  BioPtr out(BIO_new(BIO_s_mem()));
  if (!out ||
      PEM_write_bio_PrivateKey(out.get(), key, nullptr, nullptr, 0, nullptr, nullptr) != 1) {
    return opensslFailure("cannot write the private key as PEM");
  }
  return bioText(out.get());
}

Result<CertificateAndKey> loadCertificateAndKey(const std::filesystem::path& certificate_file,
                                                const std::filesystem::path& key_file,
                                                const std::string& what) {
  auto certificate = loadCertificate(certificate_file, what + "'s certificate");
  if (!certificate) {
    return Unexpected(std::move(certificate).error());
  }
  auto key = loadPrivateKey(key_file, what + "'s key");
  if (!key) {
    return Unexpected(std::move(key).error());
  }
  if (X509_check_private_key(certificate->get(), key->get()) != 1) {
    takeOpensslErrors();
    return fail(ErrorCode::kFormat, key_file.string() + ": " + what +
                                        "'s key does not belong to its certificate " +
                                        certificate_file.string());
  }
  return CertificateAndKey{std::move(*certificate), std::move(*key)};
}

Result<ValidityText> validityText(const X509* certificate) {
  auto not_before = isoText(X509_get0_notBefore(certificate), "notBefore");
  if (!not_before) {
    return Unexpected(std::move(not_before).error());
  }
  auto not_after = isoText(X509_get0_notAfter(certificate), "notAfter");
  if (!not_after) {
    return Unexpected(std::move(not_after).error());
  }
  return ValidityText{*not_before, *not_after};
}

}  // namespace raymap::security
