// SPDX-License-Identifier: BSD-3-Clause
// Fuzz target: diagnostic_msgs/DiagnosticArray as raymap echo decodes it.
#include <cstddef>
#include <cstdint>
#include <span>

#include "src/msgs/diagnostics_decode.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  auto array = raymap::msgs::decodeDiagnosticArray(
      std::span<const std::byte>(reinterpret_cast<const std::byte*>(data), size));
  if (array) {
    for (const auto& status : array->statuses) {
      (void)raymap::msgs::diagnosticLevelName(status.level);
    }
  }
  return 0;
}
