// SPDX-License-Identifier: BSD-3-Clause
// TempDir and the shared-data lookup.
#include "tests/support/temp_dir.hpp"

#include <cstdlib>
#include <stdexcept>

#include <unistd.h>

namespace raymap::test {

TempDir::TempDir() {
  const char* base = std::getenv("TMPDIR");
  std::string pattern =
      std::string(base != nullptr && *base != '\0' ? base : "/tmp") + "/raymap-test-XXXXXX";
  if (::mkdtemp(pattern.data()) == nullptr) {
    throw std::runtime_error("cannot create a temporary directory from " + pattern);
  }
  path_ = pattern;
}

TempDir::~TempDir() {
  std::error_code ignored;
  std::filesystem::remove_all(path_, ignored);
}

std::filesystem::path sharedDataDir() {
  if (const char* env = std::getenv("RAYMAP_SHARED_DATA"); env != nullptr && *env != '\0') {
    return std::filesystem::exists(env) ? std::filesystem::path(env) : std::filesystem::path();
  }
  const std::filesystem::path dir = RAYMAP_SHARED_DATA_DIR;
  return std::filesystem::exists(dir / "PROVENANCE.md") ? dir : std::filesystem::path();
}

}  // namespace raymap::test
