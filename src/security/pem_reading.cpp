// SPDX-License-Identifier: BSD-3-Clause
// Whole files, PEM certificates and private keys through OpenSSL memory BIOs.
#include "src/security/pem_reading.hpp"

#include <cerrno>

#include <fcntl.h>
#include <openssl/pem.h>
#include <unistd.h>

#include "platform/errno_text.hpp"

namespace raymap::security {
namespace {

/// A passphrase callback that gives none: an encrypted key fails instead of prompting.
int noPassphrase(char* /*buffer*/, int /*size*/, int /*rwflag*/, void* /*user*/) { return -1; }

}  // namespace

Unexpected<Error> opensslFailure(const std::string& what) {
  std::string reason = takeOpensslErrors();
  return fail(ErrorCode::kFormat, what + (reason.empty() ? "" : ": " + reason));
}

Result<std::string> readWholeFile(const std::filesystem::path& file, std::string_view what) {
  auto failed = [&](int error) {
    return fail(ErrorCode::kIo, file.string() + ": cannot read " + std::string(what) + ": " +
                                    platform::errnoText(error));
  };
  const int fd = ::open(file.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) {
    return failed(errno);
  }
  std::string content;
  char buffer[4096];
  for (;;) {
    const ssize_t n = ::read(fd, buffer, sizeof buffer);
    if (n < 0 && errno == EINTR) {
      continue;
    }
    if (n <= 0) {
      const int error = n < 0 ? errno : 0;
      ::close(fd);
      if (error != 0) {
        return failed(error);
      }
      return content;
    }
    content.append(buffer, static_cast<std::size_t>(n));
  }
}

Result<X509Ptr> loadCertificate(const std::filesystem::path& file, std::string_view what) {
  auto text = readWholeFile(file, what);
  if (!text) {
    return Unexpected(std::move(text).error());
  }
  BioPtr in = memoryBio(*text);
  X509Ptr certificate(PEM_read_bio_X509(in.get(), nullptr, noPassphrase, nullptr));
  if (!certificate) {
    return opensslFailure(file.string() + ": cannot read " + std::string(what) +
                          ": not a PEM certificate");
  }
  return certificate;
}

Result<PkeyPtr> loadPrivateKey(const std::filesystem::path& file, std::string_view what) {
  auto text = readWholeFile(file, what);
  if (!text) {
    return Unexpected(std::move(text).error());
  }
  BioPtr in = memoryBio(*text);
  PkeyPtr key(PEM_read_bio_PrivateKey(in.get(), nullptr, noPassphrase, nullptr));
  if (!key) {
    return opensslFailure(file.string() + ": cannot read " + std::string(what) +
                          ": not an unencrypted PEM private key");
  }
  return key;
}

}  // namespace raymap::security
