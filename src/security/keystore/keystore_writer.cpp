// SPDX-License-Identifier: BSD-3-Clause
// Keystores: the CA, its links, the signed governance; signing with the permissions CA; the
// list of enclaves.
#include "src/security/keystore/keystore_writer.hpp"

#include <algorithm>
#include <system_error>

#include "src/security/keystore/certificate_maker.hpp"
#include "src/security/keystore/keystore_files.hpp"
#include "src/security/keystore/keystore_layout.hpp"
#include "src/security/keystore/keystore_options.hpp"
#include "src/security/keystore/pem_files.hpp"
#include "src/security/keystore/security_documents.hpp"
#include "src/security/keystore/smime_signer.hpp"

namespace raymap::security {
namespace {

namespace files = keystore_files;

/// The texts of a new keystore's files.
struct KeystoreTexts {
  std::string ca_key;
  std::string ca_cert;
  std::string governance;
  std::string governance_p7s;
};

Result<KeystoreTexts> keystoreTexts(const KeystoreOptions& options) {
  auto ca = makeCaCertificate(options.common_name, options.ca_validity);
  if (!ca) {
    return Unexpected(std::move(ca).error());
  }
  KeystoreTexts texts;
  auto key = privateKeyPem(ca->key.get());
  auto cert = certificatePem(ca->certificate.get());
  if (!key || !cert) {
    return Unexpected(!key ? std::move(key).error() : std::move(cert).error());
  }
  texts.ca_key = std::move(*key);
  texts.ca_cert = std::move(*cert);
  texts.governance = governanceXml(options.domains);
  auto signed_text = signSmime(ca->certificate.get(), ca->key.get(), texts.governance);
  if (!signed_text) {
    return Unexpected(std::move(signed_text).error());
  }
  texts.governance_p7s = std::move(*signed_text);
  return texts;
}

/// Refuses a folder holding a keystore, or any file a keystore would overwrite.
Result<void> checkNoKeystore(const std::filesystem::path& keystore) {
  for (const char* file : {files::kCaCert, files::kGovernanceP7s}) {
    if (pathExists(keystore / file)) {
      return fail(ErrorCode::kInvalidArgument, keystore.string() + ": already holds a keystore (" +
                                                   file + " exists); nothing was changed");
    }
  }
  for (const char* file :
       {files::kCaKey, files::kIdentityCaCert, files::kIdentityCaKey, files::kPermissionsCaCert,
        files::kPermissionsCaKey, files::kGovernanceXml}) {
    if (pathExists(keystore / file)) {
      return fail(ErrorCode::kInvalidArgument,
                  (keystore / file).string() +
                      ": exists in a folder without a keystore; remove it or choose another "
                      "folder (nothing was changed)");
    }
  }
  return {};
}

Result<void> addKeystoreFiles(FileBatch& batch, const std::filesystem::path& keystore,
                              const KeystoreTexts& texts) {
  Result<void> added = batch.addFile(keystore / files::kCaKey, texts.ca_key, kPrivateFileMode);
  for (const char* link : {files::kIdentityCaKey, files::kPermissionsCaKey}) {
    added = added ? batch.addLink(keystore / link, "ca.key.pem") : added;
  }
  added = added ? batch.addFile(keystore / files::kCaCert, texts.ca_cert, kPublicFileMode) : added;
  for (const char* link : {files::kIdentityCaCert, files::kPermissionsCaCert}) {
    added = added ? batch.addLink(keystore / link, "ca.cert.pem") : added;
  }
  added = added ? batch.addFile(keystore / files::kGovernanceXml, texts.governance, kPublicFileMode)
                : added;
  // Last: with it, the keystore is complete (sros2 looks for governance.p7s).
  return added ? batch.addFile(keystore / files::kGovernanceP7s, texts.governance_p7s,
                               kPublicFileMode)
               : added;
}

}  // namespace

Result<void> createKeystore(const std::filesystem::path& keystore, const KeystoreOptions& options) {
  if (auto ok = checkDomains(options.domains); !ok) {
    return ok;
  }
  if (auto ok = checkNoKeystore(keystore); !ok) {
    return ok;
  }
  auto texts = keystoreTexts(options);
  if (!texts) {
    return Unexpected(Error{texts.error().code, keystore.string() + ": " + texts.error().message});
  }
  CreatedFolders folders;  // declared first: removed after the batch's temporaries
  FileBatch batch;
  Result<void> made = folders.create(keystore / "public");
  made = made ? folders.create(keystore / "private", kPrivateFolderMode) : made;
  made = made ? folders.create(keystore / "enclaves") : made;
  made = made ? addKeystoreFiles(batch, keystore, *texts) : made;
  made = made ? batch.commit() : made;
  if (made) {
    folders.keep();
  }
  return made;
}

Result<std::string> signWithPermissionsCa(const std::filesystem::path& keystore,
                                          std::string_view document) {
  auto ca = loadCertificateAndKey(keystore / files::kPermissionsCaCert,
                                  keystore / files::kPermissionsCaKey, "the permissions CA");
  if (!ca) {
    return Unexpected(std::move(ca).error());
  }
  auto signed_text = signSmime(ca->certificate.get(), ca->key.get(), document);
  if (!signed_text) {
    return fail(signed_text.error().code, (keystore / files::kPermissionsCaKey).string() + ": " +
                                              signed_text.error().message);
  }
  return signed_text;
}

Result<std::vector<std::string>> listEnclaves(const std::filesystem::path& keystore) {
  if (auto ok = checkKeystore(keystore); !ok) {
    return Unexpected(std::move(ok).error());
  }
  const std::filesystem::path root = keystore / "enclaves";
  std::vector<std::string> names;
  std::error_code error;
  for (auto it = std::filesystem::recursive_directory_iterator(root, error);
       !error && it != std::filesystem::recursive_directory_iterator(); it.increment(error)) {
    if (it->path().filename() != enclave_files::kKey) {
      continue;
    }
    // (append, not "/" + string: GCC 12 at -O3 flags that with a false -Wrestrict.)
    const std::string name =
        std::string("/").append(it->path().parent_path().lexically_relative(root).string());
    if (checkEnclaveName(name)) {  // not a half-written ".x.tmp-..." folder
      names.push_back(name);
    }
  }
  if (error) {
    return fail(ErrorCode::kIo, root.string() + ": cannot list the enclaves: " + error.message());
  }
  std::sort(names.begin(), names.end());
  return names;
}

}  // namespace raymap::security
