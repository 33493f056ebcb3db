// SPDX-License-Identifier: BSD-3-Clause
// The DDS domain of the DDS unit tests: 100-199 by process id, so that two test processes that run
// at once rarely share one (the end-to-end tests use 200-229).
#pragma once

#include <cstdint>

#include <unistd.h>

namespace raymap::dds {

inline std::uint32_t testDomain() { return 100U + static_cast<std::uint32_t>(getpid() % 100); }

}  // namespace raymap::dds
