// SPDX-License-Identifier: BSD-3-Clause
// The enclave checks: certificates, key, signed documents (OpenSSL) and the grant.
#include "src/security/enclave_check.hpp"

#include <openssl/pem.h>

#include "src/security/openssl_handles.hpp"
#include "src/security/pem_reading.hpp"

namespace raymap::security {
namespace {

/// A file's bytes, or an error naming it, what it is for and the reason.
Result<std::string> readFile(const std::string& path, const char* role) {
  return readWholeFile(path, std::string("the enclave's ") + role);
}

std::time_t asTime(const ASN1_TIME* time) {
  std::tm tm{};
  ASN1_TIME_to_tm(time, &tm);
  return timegm(&tm);
}

/// The certificate's validity at `now`.
Result<void> checkValidity(const X509* certificate, const std::string& path, const char* role,
                           std::time_t now) {
  const std::time_t not_before = asTime(X509_get0_notBefore(certificate));
  const std::time_t not_after = asTime(X509_get0_notAfter(certificate));
  if (now > not_after) {
    return fail(ErrorCode::kInvalidArgument,
                path + ": the " + role + " expired on " + utcText(not_after));
  }
  if (now < not_before) {
    return fail(ErrorCode::kInvalidArgument,
                path + ": the " + role + " is not valid before " + utcText(not_before));
  }
  return {};
}

/// A certificate of the enclave, read and valid at `now`.
Result<X509Ptr> validCertificate(const std::string& path, const char* role, std::time_t now) {
  auto certificate = loadCertificate(path, std::string("the enclave's ") + role);
  if (!certificate) {
    return certificate;
  }
  if (auto valid = checkValidity(certificate->get(), path, role, now); !valid) {
    return Unexpected(std::move(valid).error());
  }
  return certificate;
}

/// A store trusting `ca` alone, checking at `now`.
X509StorePtr storeOf(X509* ca, std::time_t now) {
  X509StorePtr store(X509_STORE_new());
  X509_STORE_add_cert(store.get(), ca);
  X509_VERIFY_PARAM_set_time(X509_STORE_get0_param(store.get()), now);
  return store;
}

/// Whether `certificate` chains to `ca` (the reason when not).
Result<void> checkSignedBy(X509* certificate, X509* ca, std::time_t now) {
  X509StorePtr store = storeOf(ca, now);
  X509StoreCtxPtr context(X509_STORE_CTX_new());
  X509_STORE_CTX_init(context.get(), store.get(), certificate, nullptr);
  if (X509_verify_cert(context.get()) != 1) {
    return fail(ErrorCode::kInvalidArgument,
                X509_verify_cert_error_string(X509_STORE_CTX_get_error(context.get())));
  }
  return {};
}

/// The content of an S/MIME signed document, verified against the permissions CA.
Result<std::string> verifiedDocument(const std::string& path, const char* role, X509* ca,
                                     const std::string& ca_path, std::time_t now) {
  auto text = readFile(path, role);
  if (!text) {
    return Unexpected(std::move(text).error());
  }
  BioPtr bio = memoryBio(*text);
  BIO* detached = nullptr;
  Pkcs7Ptr signature(SMIME_read_PKCS7(bio.get(), &detached));
  BioPtr content(detached);
  if (!signature) {
    return fail(ErrorCode::kFormat, path + ": the " + std::string(role) +
                                        " is not an S/MIME signed document (" +
                                        takeOpensslErrors() + ")");
  }
  X509StorePtr store = storeOf(ca, now);
  BioPtr out(BIO_new(BIO_s_mem()));
  if (PKCS7_verify(signature.get(), nullptr, store.get(), content.get(), out.get(), PKCS7_TEXT) !=
      1) {
    return fail(ErrorCode::kInvalidArgument, path + ": the " + role +
                                                 " is not signed by the permissions CA " + ca_path +
                                                 " (" + takeOpensslErrors() + ")");
  }
  return bioText(out.get());
}

struct Certificates {
  X509Ptr identity_ca;
  X509Ptr permissions_ca;
  X509Ptr identity;
};

/// The three certificates, each valid at `now`, the identity signed by its CA, the key its own.
Result<Certificates> checkIdentity(const dds::SecurityFiles& files, std::time_t now) {
  auto identity_ca = validCertificate(files.identity_ca, "identity CA", now);
  auto permissions_ca = validCertificate(files.permissions_ca, "permissions CA", now);
  auto identity = validCertificate(files.certificate, "identity certificate", now);
  for (auto* read : {&identity_ca, &permissions_ca, &identity}) {
    if (!*read) {
      return Unexpected(std::move(*read).error());
    }
  }
  Certificates c{std::move(*identity_ca), std::move(*permissions_ca), std::move(*identity)};
  if (auto signed_by = checkSignedBy(c.identity.get(), c.identity_ca.get(), now); !signed_by) {
    return fail(ErrorCode::kInvalidArgument,
                files.certificate + ": the identity certificate is not signed by the identity CA " +
                    files.identity_ca + " (" + signed_by.error().message + ")");
  }
  auto key = loadPrivateKey(files.private_key, "the enclave's private key");
  if (!key) {
    return Unexpected(std::move(key).error());
  }
  if (X509_check_private_key(c.identity.get(), key->get()) != 1) {
    takeOpensslErrors();
    return fail(ErrorCode::kInvalidArgument,
                files.private_key + ": the private key is not the one of " + files.certificate);
  }
  return c;
}

/// The grant: the certificate's subject, valid at `now`, allowing every need on `domain`.
Result<PermissionsGrant> checkGrant(const std::string& xml, const dds::SecurityFiles& files,
                                    const std::string& subject, std::uint32_t domain,
                                    std::span<const TopicNeed> needs, std::time_t now) {
  auto grant = PermissionsGrant::find(xml, subject);
  if (!grant) {
    return fail(ErrorCode::kInvalidArgument, files.permissions + ": " + grant.error().message);
  }
  if (now > grant->notAfter()) {
    return fail(ErrorCode::kInvalidArgument, files.permissions + ": the grant of " + subject +
                                                 " expired on " + utcText(grant->notAfter()));
  }
  if (now < grant->notBefore()) {
    return fail(ErrorCode::kInvalidArgument, files.permissions + ": the grant of " + subject +
                                                 " is not valid before " +
                                                 utcText(grant->notBefore()));
  }
  if (!grant->coversDomain(domain)) {
    return fail(ErrorCode::kInvalidArgument, files.permissions + ": the permissions of " + subject +
                                                 " do not cover domain " + std::to_string(domain) +
                                                 " (ROS_DOMAIN_ID / dds.domain)");
  }
  std::string refused;
  for (const TopicNeed& need : needs) {
    if (!grant->allows(domain, need.topic, need.use)) {
      refused += std::string(refused.empty() ? "" : ", ") +
                 (need.use == TopicUse::kPublish ? "publish " : "subscribe ") + need.topic;
    }
  }
  if (!refused.empty()) {
    return fail(ErrorCode::kInvalidArgument, files.permissions + ": the permissions of " + subject +
                                                 " on domain " + std::to_string(domain) +
                                                 " do not allow: " + refused);
  }
  return grant;
}

}  // namespace

std::filesystem::path enclaveFolder(const SecurityConfig& config) {
  if (!config.enclave_dir.empty()) {
    return config.enclave_dir;
  }
  return enclaveFolder(config.keystore, config.enclave);
}

dds::SecurityFiles enclaveFilesIn(const std::filesystem::path& folder) {
  const std::filesystem::path absolute = std::filesystem::absolute(folder);
  const auto file = [&](const char* name) { return (absolute / name).string(); };
  return dds::SecurityFiles{file(enclave_files::kIdentityCaCert),
                            file(enclave_files::kCert),
                            file(enclave_files::kKey),
                            file(enclave_files::kPermissionsCaCert),
                            file(enclave_files::kGovernanceP7s),
                            file(enclave_files::kPermissionsP7s)};
}

Result<EnclaveCheck> checkEnclave(const dds::SecurityFiles& files, std::uint32_t domain,
                                  std::span<const TopicNeed> needs, std::time_t now) {
  auto certificates = checkIdentity(files, now);
  if (!certificates) {
    return Unexpected(std::move(certificates).error());
  }
  X509* permissions_ca = certificates->permissions_ca.get();
  auto governance =
      verifiedDocument(files.governance, "governance", permissions_ca, files.permissions_ca, now);
  if (!governance) {
    return Unexpected(std::move(governance).error());
  }
  if (!governanceCoversDomain(*governance, domain)) {
    return fail(ErrorCode::kInvalidArgument,
                files.governance + ": the governance does not cover domain " +
                    std::to_string(domain) + " (ROS_DOMAIN_ID / dds.domain)");
  }
  auto permissions =
      verifiedDocument(files.permissions, "permissions", permissions_ca, files.permissions_ca, now);
  if (!permissions) {
    return Unexpected(std::move(permissions).error());
  }
  EnclaveCheck check;
  check.subject = subjectText(certificates->identity.get());
  auto grant = checkGrant(*permissions, files, check.subject, domain, needs, now);
  if (!grant) {
    return Unexpected(std::move(grant).error());
  }
  check.certificate_not_after = asTime(X509_get0_notAfter(certificates->identity.get()));
  check.permissions_not_after = grant->notAfter();
  return check;
}

std::string utcText(std::time_t seconds) {
  std::tm tm{};
  gmtime_r(&seconds, &tm);
  char text[32];
  std::strftime(text, sizeof text, "%Y-%m-%d %H:%M:%S UTC", &tm);
  return text;
}

}  // namespace raymap::security
