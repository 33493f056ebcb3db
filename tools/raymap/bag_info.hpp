// SPDX-License-Identifier: BSD-3-Clause
// `raymap info` on a rosbag2 recording (a directory, .mcap or .db3).
#pragma once

#include <string>

namespace raymap::cli {

/// @brief Prints the bag's storage, time span and per-topic type and message count (JSON with
/// `json`): from an indexed MCAP file's summary when it has one, else (or with `full`) by
/// reading every message, which also gives the bytes per topic. @return the process exit code.
int runBagInfo(const std::string& path, bool json, bool full);

}  // namespace raymap::cli
