// SPDX-License-Identifier: BSD-3-Clause
// X.509 v3 certificates built field by field with OpenSSL 3.
#include "src/security/keystore/certificate_maker.hpp"

#include <array>
#include <chrono>
#include <memory>
#include <string>

#include <openssl/rand.h>
#include <openssl/x509v3.h>

namespace raymap::security {
namespace {

struct ExtensionFree {
  void operator()(X509_EXTENSION* p) const noexcept { X509_EXTENSION_free(p); }
};
using ExtensionPtr = std::unique_ptr<X509_EXTENSION, ExtensionFree>;

/// OpenSSL's reason, or `fallback` when its queue is empty.
std::string reasonOr(const char* fallback) {
  std::string reason = takeOpensslErrors();
  return reason.empty() ? std::string(fallback) : reason;
}

/// 16 random bytes, positive (top bit clear) and without a leading zero byte (a minimal DER
/// INTEGER): a serial number no other certificate of this CA has.
bool setRandomSerial(X509* certificate) {
  std::array<unsigned char, 16> bytes{};
  if (RAND_bytes(bytes.data(), static_cast<int>(bytes.size())) != 1) {
    return false;
  }
  bytes[0] = static_cast<unsigned char>((bytes[0] & 0x7FU) | 0x01U);
  return ASN1_STRING_set(X509_get_serialNumber(certificate), bytes.data(),
                         static_cast<int>(bytes.size())) == 1;
}

bool setValidity(X509* certificate, const Validity& validity) {
  using std::chrono::system_clock;
  return ASN1_TIME_set(X509_getm_notBefore(certificate),
                       system_clock::to_time_t(validity.not_before)) != nullptr &&
         ASN1_TIME_set(X509_getm_notAfter(certificate),
                       system_clock::to_time_t(validity.not_after)) != nullptr;
}

bool setSubject(X509* certificate, std::string_view common_name) {
  X509_NAME* subject = X509_get_subject_name(certificate);
  return X509_NAME_add_entry_by_txt(
             subject, "CN", MBSTRING_UTF8,
             reinterpret_cast<const unsigned char*>(common_name.data()),  // OpenSSL's bytes
             static_cast<int>(common_name.size()), -1, 0) == 1;
}

bool addBasicConstraints(X509* certificate, bool ca) {
  ExtensionPtr extension(X509V3_EXT_conf_nid(nullptr, nullptr, NID_basic_constraints,
                                             ca ? "critical,CA:TRUE,pathlen:1" : "CA:FALSE"));
  return extension && X509_add_ext(certificate, extension.get(), -1) == 1;
}

/// Everything but the issuer and the signature.
Result<KeyAndCertificate> unsignedCertificate(std::string_view common_name,
                                              const Validity& validity, bool ca) {
  auto failed = [&](const char* step) {
    return fail(ErrorCode::kInvalidArgument, "certificate for CN=" + std::string(common_name) +
                                                 ": " + step + ": " + reasonOr("failed"));
  };
  if (validity.not_after <= validity.not_before) {
    return fail(ErrorCode::kInvalidArgument, "certificate for CN=" + std::string(common_name) +
                                                 ": its validity ends before it begins");
  }
  auto key = makeP256Key();
  if (!key) {
    return Unexpected(std::move(key).error());
  }
  X509Ptr certificate(X509_new());
  if (!certificate || X509_set_version(certificate.get(), 2) != 1) {  // 2: X.509 v3
    return failed("cannot make the certificate");
  }
  if (!setRandomSerial(certificate.get())) {
    return failed("cannot draw a serial number");
  }
  if (!setValidity(certificate.get(), validity)) {
    return failed("cannot set the validity");
  }
  if (!setSubject(certificate.get(), common_name)) {
    return failed("cannot set the subject (a CN holds 1 to 64 characters)");
  }
  if (X509_set_pubkey(certificate.get(), key->get()) != 1 ||
      !addBasicConstraints(certificate.get(), ca)) {
    return failed("cannot set the public key and basic constraints");
  }
  return KeyAndCertificate{std::move(*key), std::move(certificate)};
}

Result<void> signCertificate(X509* certificate, EVP_PKEY* signer, std::string_view common_name) {
  if (X509_sign(certificate, signer, EVP_sha256()) <= 0) {
    return fail(ErrorCode::kInvalidArgument, "certificate for CN=" + std::string(common_name) +
                                                 ": cannot sign it: " + reasonOr("failed"));
  }
  return {};
}

}  // namespace

Result<PkeyPtr> makeP256Key() {
  PkeyPtr key(EVP_EC_gen("P-256"));
  if (!key) {
    return fail(ErrorCode::kUnsupported,
                "cannot make an EC prime256v1 key: " + reasonOr("OpenSSL refused"));
  }
  return key;
}

Result<KeyAndCertificate> makeCaCertificate(std::string_view common_name,
                                            const Validity& validity) {
  auto made = unsignedCertificate(common_name, validity, true);
  if (!made) {
    return made;
  }
  X509* certificate = made->certificate.get();
  if (X509_set_issuer_name(certificate, X509_get_subject_name(certificate)) != 1) {
    return fail(ErrorCode::kInvalidArgument, "cannot set the CA's issuer: " + reasonOr("failed"));
  }
  if (auto signed_ok = signCertificate(certificate, made->key.get(), common_name); !signed_ok) {
    return Unexpected(std::move(signed_ok).error());
  }
  return made;
}

Result<KeyAndCertificate> makeIdentityCertificate(std::string_view name, const Validity& validity,
                                                  X509* ca_certificate, EVP_PKEY* ca_key) {
  auto made = unsignedCertificate(name, validity, false);
  if (!made) {
    return made;
  }
  X509* certificate = made->certificate.get();
  if (X509_set_issuer_name(certificate, X509_get_subject_name(ca_certificate)) != 1) {
    return fail(ErrorCode::kInvalidArgument, "certificate for CN=" + std::string(name) +
                                                 ": cannot set the issuer: " + reasonOr("failed"));
  }
  if (auto signed_ok = signCertificate(certificate, ca_key, name); !signed_ok) {
    return Unexpected(std::move(signed_ok).error());
  }
  return made;
}

}  // namespace raymap::security
