// SPDX-License-Identifier: BSD-3-Clause
// What `raymap devices` shows for each GPU API: the devices as text and JSON, or why there are
// none. One source file per API; each compiles in every build and says when the build lacks it.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "tools/raymap/json_output.hpp"

namespace raymap::cli {

/// @brief The devices of one API (value type).
struct DeviceListing {
  bool available = false;  ///< at least one device
  std::string error;       ///< why not, when !available
  std::string text;        ///< human-readable lines, each ending in '\n'
  Json json;               ///< one JSON object
};

DeviceListing listOpenClDevices();
DeviceListing listCudaDevices();

/// @brief printf into the end of a string.
__attribute__((format(printf, 2, 3))) void appendf(std::string* out, const char* format, ...);
/// @brief "1.5 GiB" / "512 MiB".
std::string sizeText(std::uint64_t bytes);

}  // namespace raymap::cli
