// SPDX-License-Identifier: BSD-3-Clause
// Telling a record log from other files by its magic.
#include "src/record/record_log.hpp"

#include <array>
#include <cstdio>
#include <cstring>
#include <string_view>

namespace raymap::record {

bool looksLikeRecordLog(const std::string& path) {
  std::FILE* file = std::fopen(path.c_str(), "rb");
  if (file == nullptr) {
    return false;
  }
  std::array<char, kRecordLogMagic.size()> start{};
  const std::size_t got = std::fread(start.data(), 1, start.size(), file);
  static_cast<void>(std::fclose(file));
  return got == start.size() && std::memcmp(start.data(), kRecordLogMagic.data(), got) == 0;
}

bool isRecordLogInput(const std::string& path) {
  constexpr std::string_view kExtension = ".rmlog";
  return (path.size() > kExtension.size() &&
          path.compare(path.size() - kExtension.size(), kExtension.size(), kExtension) == 0) ||
         looksLikeRecordLog(path);
}

}  // namespace raymap::record
