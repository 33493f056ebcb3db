// SPDX-License-Identifier: BSD-3-Clause
// Enclaves: an identity (key, certificate signed by the identity CA), links to the keystore's
// CAs and governance, and signed permissions.
#include <string>
#include <system_error>
#include <utility>

#include "src/security/keystore/certificate_maker.hpp"
#include "src/security/keystore/keystore_files.hpp"
#include "src/security/keystore/keystore_layout.hpp"
#include "src/security/keystore/keystore_options.hpp"
#include "src/security/keystore/keystore_writer.hpp"
#include "src/security/keystore/pem_files.hpp"
#include "src/security/keystore/security_documents.hpp"

namespace raymap::security {
namespace {

namespace files = enclave_files;

/// The enclave's certificate, and the PEM texts of a new identity (empty for a kept one).
struct Identity {
  X509Ptr certificate;
  std::string certificate_pem;
  std::string key_pem;
};

/// A new identity for `name`, signed by the keystore's identity CA.
Result<Identity> newIdentity(const std::filesystem::path& keystore, std::string_view name,
                             const Validity& validity) {
  auto ca = loadCertificateAndKey(keystore / keystore_files::kIdentityCaCert,
                                  keystore / keystore_files::kIdentityCaKey, "the identity CA");
  if (!ca) {
    return Unexpected(std::move(ca).error());
  }
  auto made = makeIdentityCertificate(name, validity, ca->certificate.get(), ca->key.get());
  if (!made) {
    return Unexpected(std::move(made).error());
  }
  auto key = privateKeyPem(made->key.get());
  auto cert = certificatePem(made->certificate.get());
  if (!key || !cert) {
    return Unexpected(!key ? std::move(key).error() : std::move(cert).error());
  }
  return Identity{std::move(made->certificate), std::move(*cert), std::move(*key)};
}

/// The identity the enclave has (key and certificate kept, as sros2), else a new one.
Result<Identity> enclaveIdentity(const std::filesystem::path& keystore,
                                 const std::filesystem::path& folder, std::string_view name,
                                 const Validity& validity) {
  std::error_code error;
  if (std::filesystem::is_regular_file(folder / files::kCert, error) &&
      std::filesystem::is_regular_file(folder / files::kKey, error)) {
    auto kept = loadCertificate(folder / files::kCert, "the enclave's certificate");
    if (!kept) {
      return Unexpected(std::move(kept).error());
    }
    return Identity{std::move(*kept), {}, {}};
  }
  return newIdentity(keystore, name, validity);
}

/// A new identity's files; key.pem last, so a listed enclave is a complete one.
Result<void> addIdentity(FileBatch& batch, const std::filesystem::path& folder,
                         const Identity& identity) {
  if (identity.key_pem.empty()) {
    return {};
  }
  Result<void> added =
      batch.addFile(folder / files::kCert, identity.certificate_pem, kPublicFileMode);
  return added ? batch.addFile(folder / files::kKey, identity.key_pem, kPrivateFileMode) : added;
}

Result<void> addLinks(FileBatch& batch, const std::filesystem::path& folder,
                      std::string_view name) {
  Result<void> added;
  for (const auto& [link, target] :
       {std::pair{files::kIdentityCaCert, keystore_files::kIdentityCaCert},
        std::pair{files::kPermissionsCaCert, keystore_files::kPermissionsCaCert},
        std::pair{files::kGovernanceP7s, keystore_files::kGovernanceP7s}}) {
    added = added ? batch.addLink(folder / link, fromEnclaveTo(name, target)) : added;
  }
  return added;
}

Result<void> addPermissions(FileBatch& batch, const std::filesystem::path& keystore,
                            const std::filesystem::path& folder, const EnclaveGrant& grant,
                            const DomainRange& domains, const X509* certificate) {
  auto validity = validityText(certificate);
  if (!validity) {
    return fail(validity.error().code,
                (folder / files::kCert).string() + ": " + validity.error().message);
  }
  const std::string xml = permissionsXml(grant, domains, *validity);
  auto signed_xml = signWithPermissionsCa(keystore, xml);
  if (!signed_xml) {
    return Unexpected(std::move(signed_xml).error());
  }
  Result<void> added = batch.addFile(folder / files::kPermissionsXml, xml, kPublicFileMode);
  return added ? batch.addFile(folder / files::kPermissionsP7s, *signed_xml, kPublicFileMode)
               : added;
}

Result<void> checkGrant(const std::filesystem::path& keystore, const EnclaveGrant& grant,
                        const EnclaveOptions& options) {
  if (auto ok = checkDomains(options.domains); !ok) {
    return ok;
  }
  if (auto ok = checkEnclaveName(grant.enclave); !ok) {
    return ok;
  }
  for (const auto* topics : {&grant.publish, &grant.subscribe}) {
    for (const std::string& topic : *topics) {
      if (topic.empty()) {
        return fail(ErrorCode::kInvalidArgument,
                    "enclave " + grant.enclave + ": an empty topic name in its grant");
      }
    }
  }
  return checkKeystore(keystore);
}

/// The enclave's files (a new identity only when it has none), all renamed into place together
/// at the end.
Result<void> writeEnclave(const std::filesystem::path& keystore, const EnclaveGrant& grant,
                          const EnclaveOptions& options) {
  if (auto ok = checkGrant(keystore, grant, options); !ok) {
    return ok;
  }
  const std::filesystem::path folder = enclaveFolder(keystore, grant.enclave);
  auto identity = enclaveIdentity(keystore, folder, grant.enclave, options.validity);
  if (!identity) {
    return Unexpected(std::move(identity).error());
  }
  CreatedFolders folders;  // declared first: removed after the batch's temporaries
  FileBatch batch;
  Result<void> made = folders.create(folder);
  made = made ? addLinks(batch, folder, grant.enclave) : made;
  made = made ? addPermissions(batch, keystore, folder, grant, options.domains,
                               identity->certificate.get())
              : made;
  made = made ? addIdentity(batch, folder, *identity) : made;
  made = made ? batch.commit() : made;
  if (made) {
    folders.keep();
  }
  return made;
}

}  // namespace

Result<void> createEnclave(const std::filesystem::path& keystore, std::string_view name,
                           const EnclaveOptions& options) {
  return writeEnclave(keystore, allowEverythingGrant(name), options);
}

Result<void> writePermissions(const std::filesystem::path& keystore, const EnclaveGrant& grant,
                              const EnclaveOptions& options) {
  return writeEnclave(keystore, grant, options);
}

}  // namespace raymap::security
