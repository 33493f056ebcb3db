// SPDX-License-Identifier: BSD-3-Clause
// A global map's region pool sized to what the machine can hold (raymap populate, the library).
#pragma once

#include <string>

#include "src/map/voxel_map.hpp"

namespace raymap::mapper {

/// Sizes a global map's region pool to what this machine can hold. The pool itself is address
/// space, committed as regions are written, but every slot costs bookkeeping up front (the
/// index, the free list, the CPU workers' tables: about 160 bytes) and a region commits at least
/// its non-zero-clearing layers when it is created, so more slots than memory can fill would
/// only cost memory (a 64 TiB budget used to be killed by the OOM killer before the first
/// ray). @return a note (naming map.max_memory) when the pool was limited, else empty.
std::string fitPoolToMemory(MapConfig& map);

}  // namespace raymap::mapper
