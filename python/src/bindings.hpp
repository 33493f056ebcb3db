// SPDX-License-Identifier: BSD-3-Clause
// The parts of raymap._raymap, each registered on the module by its own file.
#pragma once

#include "mapper_handle.hpp"
#include <pybind11/pybind11.h>

namespace raymap::python {

/// The exception types of raymap/__init__.py (set once at import) and how errors become them.
void bindErrors(pybind11::module_& m);
/// MapperConfig and its parts (MapOptions, RayOptions, BackendOptions …) with read-write fields.
void bindConfig(pybind11::module_& m);
/// raymap::Mapper: integration from NumPy arrays, queries, save and load.
void bindMapper(pybind11::module_& m);
/// Height maps and costmaps: their layers as 2-D NumPy arrays.
void bindGrids(pybind11::module_& m);
/// Mapper.heightmap() and Mapper.costmap() (bindGrids first).
void addGridQueries(pybind11::class_<MapperHandle>& c);
/// CameraIntrinsics, DepthOptions and Mapper.integrate_depth() (on the class bindMapper makes).
void bindDepth(pybind11::module_& m, pybind11::class_<MapperHandle>& c);
/// raymap::RecordingReader: the scans of a bag or a ray/point-cloud file as NumPy arrays.
void bindRecording(pybind11::module_& m);

}  // namespace raymap::python
