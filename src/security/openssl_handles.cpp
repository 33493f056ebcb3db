// SPDX-License-Identifier: BSD-3-Clause
// OpenSSL's error queue as text, memory BIOs, certificate subjects.
#include "src/security/openssl_handles.hpp"

#include <openssl/err.h>

namespace raymap::security {

std::string takeOpensslErrors() {
  std::string text;
  while (const unsigned long code = ERR_get_error()) {
    char buffer[256];
    ERR_error_string_n(code, buffer, sizeof buffer);
    if (!text.empty()) {
      text += "; ";
    }
    text += buffer;
  }
  return text;
}

BioPtr memoryBio(std::string_view bytes) {
  return BioPtr(BIO_new_mem_buf(bytes.data(), static_cast<int>(bytes.size())));
}

std::string bioText(BIO* bio) {
  char* data = nullptr;
  const long size = BIO_get_mem_data(bio, &data);
  return size > 0 && data != nullptr ? std::string(data, static_cast<std::size_t>(size))
                                     : std::string();
}

std::string subjectText(const X509* certificate) {
  BioPtr out(BIO_new(BIO_s_mem()));
  // RFC 2253 without the escaping of '/', most significant attribute first: "CN=/a/b" for the
  // one-attribute subjects SROS2 makes, "C=DE, O=x, CN=y" otherwise (comma-space separated as
  // the DDS Security examples write them).
  constexpr unsigned long kFlags =
      (XN_FLAG_RFC2253 & ~XN_FLAG_DN_REV & ~ASN1_STRFLGS_ESC_MSB & ~XN_FLAG_SEP_MASK) |
      XN_FLAG_SEP_CPLUS_SPC;
  X509_NAME_print_ex(out.get(), X509_get_subject_name(certificate), 0, kFlags);
  return bioText(out.get());
}

}  // namespace raymap::security
