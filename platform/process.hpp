// SPDX-License-Identifier: BSD-3-Clause
// Facts about the running process and its terminal.
#pragma once

#include <cstdint>
#include <string>

namespace raymap::platform {

/// @brief Peak resident set size of this process so far, in bytes (0 if unknown).
std::uint64_t peakResidentBytes() noexcept;

/// @brief CPU seconds this process has used so far, every thread together (0 if unknown).
double processCpuSeconds() noexcept;

/// @brief CPU seconds the calling thread has used so far (0 if unknown).
double threadCpuSeconds() noexcept;

/// @brief True when standard error is an interactive terminal (progress bars go there).
bool stderrIsTerminal() noexcept;

/// @brief Number of hardware threads the process may run on (at least 1).
unsigned availableCores() noexcept;

/// @brief The processor's model name (for benchmark records), or "unknown".
std::string cpuModelName();

}  // namespace raymap::platform
