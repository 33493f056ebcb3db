// SPDX-License-Identifier: BSD-3-Clause
// Owners of OpenSSL objects (certificates, keys, memory buffers, signed documents) and the text
// of OpenSSL's error queue, shared by the keystore writer and the enclave checks.
#pragma once

#include <memory>
#include <string>
#include <string_view>

#include <openssl/bio.h>
#include <openssl/evp.h>
#include <openssl/pkcs7.h>
#include <openssl/x509.h>
#include <openssl/x509_vfy.h>

namespace raymap::security {

struct BioFree {
  void operator()(BIO* p) const noexcept { BIO_free_all(p); }
};
struct X509Free {
  void operator()(X509* p) const noexcept { X509_free(p); }
};
struct PkeyFree {
  void operator()(EVP_PKEY* p) const noexcept { EVP_PKEY_free(p); }
};
struct Pkcs7Free {
  void operator()(PKCS7* p) const noexcept { PKCS7_free(p); }
};
struct X509StoreFree {
  void operator()(X509_STORE* p) const noexcept { X509_STORE_free(p); }
};
struct X509StoreCtxFree {
  void operator()(X509_STORE_CTX* p) const noexcept { X509_STORE_CTX_free(p); }
};

using BioPtr = std::unique_ptr<BIO, BioFree>;
using X509Ptr = std::unique_ptr<X509, X509Free>;
using PkeyPtr = std::unique_ptr<EVP_PKEY, PkeyFree>;
using Pkcs7Ptr = std::unique_ptr<PKCS7, Pkcs7Free>;
using X509StorePtr = std::unique_ptr<X509_STORE, X509StoreFree>;
using X509StoreCtxPtr = std::unique_ptr<X509_STORE_CTX, X509StoreCtxFree>;

/// @brief OpenSSL's queued errors for this thread as one line ("" when none), and the queue
/// cleared: for the reason part of an error message. Thread-safety: per thread (OpenSSL's queue
/// is thread-local).
std::string takeOpensslErrors();

/// @brief A read-only memory BIO over `bytes` (which must outlive it).
BioPtr memoryBio(std::string_view bytes);

/// @brief What a memory BIO holds, as a string.
std::string bioText(BIO* bio);

/// @brief The one-line form of a certificate's subject, e.g. "CN=/raymap/raymapd" (RFC 2253
/// order reversed to OpenSSL's oneline form without its leading slash: what DDS Security's
/// permissions documents put in <subject_name>).
std::string subjectText(const X509* certificate);

}  // namespace raymap::security
