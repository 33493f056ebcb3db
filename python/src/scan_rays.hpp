// SPDX-License-Identifier: BSD-3-Clause
// A recording's scan (or a bag's cloud) as Python holds it: the rays (points and poses) in the
// library's own layout, owned by a named capsule; the NumPy arrays are read-only views of them,
// and Mapper.integrate_scan() (integrate_cloud()) hands the buffer to the library as it is (no
// conversion, no copy).
#pragma once

#include <vector>

#include "raymap/recording.hpp"
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

/// The capsule name that marks a RecordedCloud.
inline constexpr const char* kRecordedCloudCapsule = "raymap.recorded_cloud";

/// @brief `cloud` moved into a capsule that owns it.
pybind11::capsule ownCloud(RecordedCloud cloud);

/// @brief The cloud of a capsule made by ownCloud(); raises raymap.InvalidArgument for any
/// other object.
const RecordedCloud& cloudOf(const pybind11::object& capsule);

}  // namespace raymap::python
