// SPDX-License-Identifier: BSD-3-Clause
// Height maps and costmaps for Python: each layer a 2-D NumPy array over the result's own
// storage (no copy; read-only). A height map's arrays are (cells_x, cells_y) in grid_map's
// layout (column-major, [i, j] is cell (i, j): i along -x, j along -y from the +x/+y corner); a
// costmap's are (height, width) in nav_msgs/OccupancyGrid's (row-major, [y, x], row 0 at -y).
#include <array>
#include <cmath>
#include <optional>
#include <utility>
#include <vector>

#include "arrays.hpp"
#include "bindings.hpp"
#include "errors.hpp"
#include "raymap/heightmap.hpp"
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

namespace py = pybind11;

namespace raymap::python {
namespace {

/// The getter of a height-map layer: a (cells_x, cells_y) column-major array of `T` over the
/// result's own vector (HeightCell is one byte, read as uint8).
template <class T, class Element>
auto gridLayerOf(std::vector<Element> HeightMap::*layer) {
  static_assert(sizeof(T) == sizeof(Element));
  return [layer](const py::object& self) {
    const auto& map = self.cast<const HeightMap&>();
    const auto item = static_cast<py::ssize_t>(sizeof(T));
    const auto* data = reinterpret_cast<const T*>((map.*layer).data());
    return arrayOver<T>(data, {map.cells_x, map.cells_y}, {item, item * map.cells_x}, self);
  };
}

void bindHeightMap(py::module_& m) {
  py::class_<HeightMap>(m, "HeightMap",
                        "A 2.5D height map; layers are (cells_x, cells_y) arrays in grid_map's "
                        "layout: [i, j] is the cell i along -x and j along -y from the +x/+y "
                        "corner. World frame, metres.")
      .def_readonly("resolution", &HeightMap::resolution, "cell edge, metres")
      .def_readonly("cells_x", &HeightMap::cells_x)
      .def_readonly("cells_y", &HeightMap::cells_y)
      .def_property_readonly(
          "centre", [](const HeightMap& h) { return std::make_pair(h.centre.x(), h.centre.y()); },
          "world (x, y) of the grid's centre")
      .def_property_readonly("elevation", gridLayerOf<float>(&HeightMap::elevation),
                             "world z of the supporting surface, float32; NaN where none")
      .def_property_readonly(
          "clearance", gridLayerOf<float>(&HeightMap::clearance),
          "free height above the surface, float32; inf: open to the top; NaN: no surface")
      .def_property_readonly("kind", gridLayerOf<std::uint8_t>(&HeightMap::kind),
                             "uint8: 0 unknown, 1 surface, 2 virtual surface, 3 vacant")
      .def_property_readonly("observed_count",
                             gridLayerOf<std::uint32_t>(&HeightMap::observed_count),
                             "samples in each surface voxel, uint32")
      .def(
          "cell_centre",
          [](const HeightMap& h, int i, int j) {
            const Eigen::Vector2d c = h.cellCentre(i, j);
            return std::make_pair(c.x(), c.y());
          },
          py::arg("i"), py::arg("j"), "world (x, y) of cell [i, j]");
}

void bindCostmap(py::module_& m) {
  py::class_<Costmap>(m, "Costmap",
                      "A Nav2 costmap: cells (height, width) int8 in OccupancyGrid's layout, "
                      "[y, x], row 0 along -y; -1 unknown, 0..99 free by slope, 100 lethal.")
      .def_readonly("resolution", &Costmap::resolution)
      .def_readonly("width", &Costmap::width)
      .def_readonly("height", &Costmap::height)
      .def_property_readonly(
          "origin", [](const Costmap& c) { return std::make_pair(c.origin.x(), c.origin.y()); },
          "world (x, y) of cell [0, 0]'s -x/-y corner")
      .def_property_readonly("cells", [](const py::object& self) {
        const auto& c = self.cast<const Costmap&>();
        const auto item = static_cast<py::ssize_t>(sizeof(std::int8_t));
        return arrayOver<std::int8_t>(c.cells.data(), {c.height, c.width}, {item * c.width, item},
                                      self);
      });
  py::class_<CostmapOptions>(m, "CostmapOptions", "raymapd's costmap: section (metres, degrees).")
      .def(py::init<>())
      .def_readwrite("max_step", &CostmapOptions::max_step)
      .def_readwrite("max_slope_deg", &CostmapOptions::max_slope_deg)
      .def_readwrite("min_clearance", &CostmapOptions::min_clearance)
      .def_readwrite("virtual_lethal", &CostmapOptions::virtual_lethal)
      .def_readwrite("max_free_cost", &CostmapOptions::max_free_cost);
}

void bindRequest(py::module_& m) {
  py::class_<HeightmapRequest>(m, "HeightmapRequest",
                               "What height map to make (world frame, metres).")
      .def(py::init<>())
      .def_property(
          "centre",
          [](const HeightmapRequest& r) {
            return std::array<double, 3>{r.centre.x(), r.centre.y(), r.centre.z()};
          },
          [](HeightmapRequest& r, const std::array<double, 3>& c) {
            r.centre = Eigen::Vector3d(c[0], c[1], c[2]);
          },
          "x, y: the column the map is centred on; z: the height the surface is searched around")
      .def_readwrite("size", &HeightmapRequest::size, "side of the square map, metres")
      .def_readwrite("follow_terrain", &HeightmapRequest::follow_terrain)
      .def_readwrite("min_clearance", &HeightmapRequest::min_clearance)
      .def_readwrite("floor_depth", &HeightmapRequest::floor_depth)
      .def_readwrite("ceiling_height", &HeightmapRequest::ceiling_height)
      .def_readwrite("virtual_surfaces", &HeightmapRequest::virtual_surfaces);
}

}  // namespace

void bindGrids(py::module_& m) {
  bindRequest(m);
  bindHeightMap(m);
  bindCostmap(m);
}

void addGridQueries(py::class_<MapperHandle>& c) {
  c.def(
       "heightmap",
       [](MapperHandle& self, const HeightmapRequest& request) {
         return valueOr(
             withMapper(self, [&](Mapper& mapper) { return mapper.heightmap(request); }));
       },
       py::arg("request"), "The height map `request` asks for (as raymap heightmap makes it).")
      .def(
          "costmap",
          [](MapperHandle& self, const HeightmapRequest& request, const CostmapOptions& options) {
            return valueOr(
                withMapper(self, [&](Mapper& mapper) { return mapper.costmap(request, options); }));
          },
          py::arg("request"), py::arg("options"),
          "The Nav2 costmap of the height map `request` asks for (as raymapd publishes it).");
}

}  // namespace raymap::python
