// SPDX-License-Identifier: BSD-3-Clause
// A recording's scan (or a bag's cloud) as Python holds it: the rays (points and poses) in the
// library's own layout, owned by a named capsule; the NumPy arrays are read-only views of them,
// and Mapper.integrate_scan() (integrate_cloud()) hands the buffer to the library as it is (no
// conversion, no copy).
#pragma once

#include <utility>
#include <vector>

#include "raymap/recording.hpp"
#include "raymap/scan.hpp"
#include <pybind11/pybind11.h>

namespace raymap::python {

struct ScanRays {
  std::vector<WorldRay> rays;
};

/// @brief `value` moved into a capsule named `name` that owns (and deletes) it.
template <class T>
pybind11::capsule ownInCapsule(T value, const char* name) {
  // The name outlives the capsule: every caller passes a string literal.
  return pybind11::capsule(new T(std::move(value)), name, [](PyObject* capsule) {
    delete static_cast<T*>(PyCapsule_GetPointer(capsule, PyCapsule_GetName(capsule)));
  });
}

/// @brief The value in a capsule made by ownInCapsule<T>(…, name), or nullptr for any other
/// object.
template <class T>
const T* inCapsule(const pybind11::object& object, const char* name) {
  if (!PyCapsule_IsValid(object.ptr(), name)) {
    return nullptr;
  }
  return static_cast<const T*>(PyCapsule_GetPointer(object.ptr(), name));
}

/// The capsule name that marks a ScanRays.
inline constexpr const char* kScanRaysCapsule = "raymap.scan_rays";

/// @brief The rays of a capsule made by ownInCapsule(ScanRays, kScanRaysCapsule); raises
/// raymap.InvalidArgument for any other object.
const ScanRays& scanRaysOf(const pybind11::object& capsule);

/// The capsule name that marks a RecordedCloud.
inline constexpr const char* kRecordedCloudCapsule = "raymap.recorded_cloud";

/// @brief The cloud of a capsule made by ownInCapsule(RecordedCloud, kRecordedCloudCapsule);
/// raises raymap.InvalidArgument for any other object.
const RecordedCloud& cloudOf(const pybind11::object& capsule);

}  // namespace raymap::python
