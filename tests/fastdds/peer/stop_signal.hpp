// SPDX-License-Identifier: BSD-3-Clause
// SIGINT and SIGTERM end the peer's run early; it still prints what it counted.
#pragma once

namespace raymap::fastdds_peer {

/// @brief Installs handlers of SIGINT and SIGTERM that set the stop flag.
void installStopHandlers();

/// @brief True once SIGINT or SIGTERM has arrived.
bool stopRequested() noexcept;

}  // namespace raymap::fastdds_peer
