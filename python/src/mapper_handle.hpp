// SPDX-License-Identifier: BSD-3-Clause
// A raymap::Mapper owned by Python, with the lock that serialises the Python threads using it.
#pragma once

#include <memory>
#include <mutex>
#include <utility>
#include <vector>

#include "raymap/mapper.hpp"
#include <pybind11/pybind11.h>

namespace raymap::python {

/// @brief What raymap._Mapper wraps. Every call that touches the map holds `mutex` (taken after
/// the GIL is released, so a thread waiting for it never blocks the interpreter).
struct MapperHandle {
  explicit MapperHandle(Mapper m) : mapper(std::move(m)), mutex(std::make_unique<std::mutex>()) {}
  Mapper mapper;
  std::unique_ptr<std::mutex> mutex;
  /// The library's rays and points built from a scan's arrays, kept between calls (under the
  /// lock): once grown to the largest scan, a scan costs no allocation and no page faults.
  std::vector<WorldRay> ray_staging;
  std::vector<SensorPoint> point_staging;
};

/// @brief fn(mapper) with the GIL released and the mapper's lock held: the calls that integrate,
/// flush, query, make grids or write files.
template <class Fn>
auto withMapper(MapperHandle& self, Fn&& fn) {
  const pybind11::gil_scoped_release release;
  const std::lock_guard lock(*self.mutex);
  return fn(self.mapper);
}

}  // namespace raymap::python
