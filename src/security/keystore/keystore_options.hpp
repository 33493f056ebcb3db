// SPDX-License-Identifier: BSD-3-Clause
// Checks of the keystore writer's options.
#pragma once

#include "raymap/error.hpp"

#include "src/security/keystore/keystore_writer.hpp"

namespace raymap::security {

/// @brief Checks min <= max <= 232; the error quotes the range.
Result<void> checkDomains(const DomainRange& domains);

}  // namespace raymap::security
