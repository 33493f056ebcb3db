// SPDX-License-Identifier: BSD-3-Clause
// A recording's scan as Python holds it: the rays in the library's own layout, owned by a named
// capsule; the scan's NumPy arrays are read-only views of them, and Mapper.integrate_scan() hands
// the buffer to the library as it is (no conversion, no copy).
#pragma once

#include <vector>

#include "raymap/scan.hpp"
#include <pybind11/pybind11.h>

namespace raymap::python {

struct ScanRays {
  std::vector<WorldRay> rays;
};

/// The capsule name that marks a ScanRays.
inline constexpr const char* kScanRaysCapsule = "raymap.scan_rays";

/// @brief `rays` moved into a capsule that owns them.
pybind11::capsule ownScanRays(std::vector<WorldRay> rays);

/// @brief The rays of a capsule made by ownScanRays(); raises raymap.InvalidArgument for any
/// other object.
const ScanRays& scanRaysOf(const pybind11::object& capsule);

}  // namespace raymap::python
