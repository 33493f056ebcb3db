// SPDX-License-Identifier: BSD-3-Clause
// Fuzz target: raymapd's YAML configuration (every key, range and cross-check).
#include <cstddef>
#include <cstdint>
#include <string>

#include "src/service/daemon_config.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  (void)raymap::service::parseDaemonConfig(text, "fuzz.yaml");
  return 0;
}
