// SPDX-License-Identifier: BSD-3-Clause
// What the peer prints when it ends: one JSON object, built with nlohmann.
#pragma once

#include <nlohmann/json.hpp>

namespace raymap::fastdds_peer {

/// The peer's report: members stay in the order they are set (the order docs/fastdds-peer.md
/// describes them in); non-finite numbers are written as null.
using Json = nlohmann::ordered_json;

}  // namespace raymap::fastdds_peer
