// SPDX-License-Identifier: BSD-3-Clause
#include "src/core/byte_size.hpp"

#include <cmath>
#include <cstdlib>

namespace raymap {

Result<std::uint64_t> parseByteSize(const std::string& text) {
  char* end = nullptr;
  const double value = std::strtod(text.c_str(), &end);
  if (text.empty() || end == text.c_str() || std::isspace(static_cast<unsigned char>(text[0]))) {
    return fail(ErrorCode::kInvalidArgument, "'" + text + "' is not a size (try 4GiB or 512MiB)");
  }
  const std::string unit(end);
  double scale = 1.0;
  if (unit.empty() || unit == "B") {
    scale = 1.0;
  } else if (unit == "K" || unit == "KiB" || unit == "k") {
    scale = 1024.0;
  } else if (unit == "M" || unit == "MiB") {
    scale = 1024.0 * 1024.0;
  } else if (unit == "G" || unit == "GiB") {
    scale = 1024.0 * 1024.0 * 1024.0;
  } else if (unit == "T" || unit == "TiB") {
    scale = 1024.0 * 1024.0 * 1024.0 * 1024.0;
  } else {
    return fail(ErrorCode::kInvalidArgument,
                "unknown size unit '" + unit + "' in '" + text + "' (use B, KiB, MiB, GiB, TiB)");
  }
  const double bytes = value * scale;
  if (!std::isfinite(bytes) || bytes < 0.0 || bytes > 1.8e19) {
    return fail(ErrorCode::kInvalidArgument, "size '" + text + "' is out of range");
  }
  return static_cast<std::uint64_t>(bytes);
}

Result<CacheSize> parseCacheSize(const std::string& text) {
  CacheSize size;
  if (text == "auto") {
    return size;
  }
  const std::string suffix = "regions";
  if (text.size() > suffix.size() && text.ends_with(suffix)) {
    const std::string digits = text.substr(0, text.size() - suffix.size());
    char* end = nullptr;
    const unsigned long long n = std::strtoull(digits.c_str(), &end, 10);
    if (digits.empty() || end != digits.c_str() + digits.size() || n == 0 || n > 0xFFFFFFFFull ||
        digits[0] == '-' || digits[0] == '+') {
      return fail(ErrorCode::kInvalidArgument,
                  "'" + text + "' is not a region count such as 2000regions");
    }
    size.regions = static_cast<std::uint32_t>(n);
    return size;
  }
  auto bytes = parseByteSize(text);
  if (!bytes) {
    return Unexpected(bytes.error());
  }
  size.bytes = *bytes;
  return size;
}

}  // namespace raymap
