// SPDX-License-Identifier: BSD-3-Clause
// The levels of diagnostic_msgs/DiagnosticStatus, shared by the decoder (src/msgs) and the DDS
// sample raymapd fills (src/dds/diagnostics_message.hpp).
#pragma once

#include <cstdint>

namespace raymap::msgs {

/// DiagnosticStatus levels (diagnostic_msgs/DiagnosticStatus constants).
inline constexpr std::uint8_t kDiagnosticOk = 0;
inline constexpr std::uint8_t kDiagnosticWarn = 1;
inline constexpr std::uint8_t kDiagnosticError = 2;
inline constexpr std::uint8_t kDiagnosticStale = 3;

}  // namespace raymap::msgs
