// SPDX-License-Identifier: BSD-3-Clause
// Reads a fuzzed file as a ray source to the end, as raymap populate does.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

namespace raymap::fuzz {

/// @brief Opens `path` with openRaySource() (with a fixed trajectory, so that point clouds without
/// sensor origins are read too) and reads every ray, a chunk at a time; aborts only on
/// impossible results (more rays in one read than asked for). Errors are the expected outcome.
void readRaySource(const std::string& path);

}  // namespace raymap::fuzz
