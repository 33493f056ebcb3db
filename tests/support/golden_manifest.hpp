// SPDX-License-Identifier: BSD-3-Clause
// Golden manifests (tests/golden/*.sha256, sha256sum's format): what the golden-output tests
// compare files with.
#pragma once

#include <map>
#include <string>

namespace raymap::test {

/// @brief name -> SHA-256 (hex) of each "SHA  NAME" line of the manifest at `path`; empty when
/// it cannot be read.
std::map<std::string, std::string> readSha256Manifest(const std::string& path);

/// @brief The SHA-256 (64 hex digits) of the file at `path`, by sha256sum (coreutils: the
/// library has no SHA-256 of its own); empty when that fails.
std::string sha256OfFile(const std::string& path);

}  // namespace raymap::test
