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

HeightmapRequest toRequest(const std::array<double, 3>& centre, double size, bool follow_terrain,
                           double min_clearance, std::optional<double> floor_depth,
                           std::optional<double> ceiling_height, bool virtual_surfaces) {
  HeightmapRequest r;
  r.centre = Eigen::Vector3d(centre[0], centre[1], centre[2]);
  r.size = size;
  r.follow_terrain = follow_terrain;
  r.min_clearance = min_clearance;
  r.floor_depth = floor_depth;
  r.ceiling_height = ceiling_height;
  r.virtual_surfaces = virtual_surfaces;
  return r;
}

}  // namespace

void bindGrids(py::module_& m) {
  bindHeightMap(m);
  bindCostmap(m);
}

void addGridQueries(py::class_<MapperHandle>& c) {
  const HeightmapRequest defaults;
  c.def(
       "heightmap",
       [](MapperHandle& self, const std::array<double, 3>& centre, double size, bool follow_terrain,
          double min_clearance, std::optional<double> floor_depth,
          std::optional<double> ceiling_height, bool virtual_surfaces) {
         const HeightmapRequest request = toRequest(centre, size, follow_terrain, min_clearance,
                                                    floor_depth, ceiling_height, virtual_surfaces);
         Result<HeightMap> made = [&] {
           py::gil_scoped_release release;
           const std::lock_guard lock(*self.mutex);
           return self.mapper.heightmap(request);
         }();
         return valueOr(std::move(made));
       },
       py::arg("centre"), py::arg("size") = defaults.size,
       py::arg("follow_terrain") = defaults.follow_terrain,
       py::arg("min_clearance") = defaults.min_clearance, py::arg("floor_depth") = py::none(),
       py::arg("ceiling_height") = py::none(),
       py::arg("virtual_surfaces") = defaults.virtual_surfaces,
       "The height map around centre (x, y, z), size metres square (as raymap heightmap).")
      .def(
          "costmap",
          [](MapperHandle& self, const std::array<double, 3>& centre, double size,
             bool follow_terrain, double min_clearance, std::optional<double> floor_depth,
             std::optional<double> ceiling_height, bool virtual_surfaces,
             const CostmapOptions& options) {
            const HeightmapRequest request =
                toRequest(centre, size, follow_terrain, min_clearance, floor_depth, ceiling_height,
                          virtual_surfaces);
            Result<Costmap> made = [&] {
              py::gil_scoped_release release;
              const std::lock_guard lock(*self.mutex);
              return self.mapper.costmap(request, options);
            }();
            return valueOr(std::move(made));
          },
          py::arg("centre"), py::arg("size") = defaults.size,
          py::arg("follow_terrain") = defaults.follow_terrain,
          py::arg("min_clearance") = defaults.min_clearance, py::arg("floor_depth") = py::none(),
          py::arg("ceiling_height") = py::none(),
          py::arg("virtual_surfaces") = defaults.virtual_surfaces,
          py::arg("options") = CostmapOptions{},
          "The Nav2 costmap of the height map (as raymapd publishes it).");
}

}  // namespace raymap::python
