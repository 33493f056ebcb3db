// SPDX-License-Identifier: BSD-3-Clause
// raymap._raymap: the compiled half of the Python package (python/raymap/__init__.py is the
// other).
#include "bindings.hpp"
#include "raymap/version.hpp"
#include <pybind11/pybind11.h>

PYBIND11_MODULE(_raymap, m) {
  m.doc() = "raymap's C++ library (raymap::Mapper and its configuration); use `import raymap`.";
  m.attr("__version__") = RAYMAP_VERSION_STRING;
  raymap::python::bindErrors(m);
  raymap::python::bindConfig(m);
  raymap::python::bindGrids(m);
  raymap::python::bindMapper(m);
  raymap::python::bindRecording(m);
}
