// SPDX-License-Identifier: BSD-3-Clause
// raymap::Mapper for Python. Arrays are read in place (arrays.hpp) and the scans built and
// integrated with the GIL released, so other Python threads run meanwhile; a mutex per mapper
// keeps two Python threads from integrating into one map at once (Mapper is not thread-safe).
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <mutex>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "arrays.hpp"
#include "bindings.hpp"
#include "errors.hpp"
#include "mapper_handle.hpp"
#include "raymap/export.hpp"
#include "raymap/mapper.hpp"
#include "scan_rays.hpp"
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "src/mapper/mapper_yaml.hpp"

namespace py = pybind11;

namespace raymap::python {
namespace {

/// The points of the arrays in the handle's staging vector (every field set).
std::span<const SensorPoint> sensorPoints(const Points3View& points,
                                          const std::optional<ValuesView>& times,
                                          const std::optional<ValuesView>& intensities,
                                          std::vector<SensorPoint>& scan) {
  scan.resize(points.size());
  for (std::size_t i = 0; i < scan.size(); ++i) {
    scan[i].position = points[i];
    scan[i].time_s = times ? (*times)[i] : 0.0;
    scan[i].intensity = intensities ? static_cast<float>((*intensities)[i]) : 0.0f;
    scan[i].no_return = false;
  }
  return scan;
}

std::optional<ValuesView> optionalValues(const std::optional<py::array>& array, const char* what,
                                         std::size_t rows) {
  if (!array) {
    return std::nullopt;
  }
  return ValuesView(*array, what, rows);
}

void integratePoints(MapperHandle& self, const py::array& points, const py::array& pose,
                     const std::optional<py::array>& intensities) {
  const Points3View view(points, "points");
  const Eigen::Isometry3d sensor_to_world = toIsometry(pose, "pose");
  const std::optional<ValuesView> intensity =
      optionalValues(intensities, "intensities", view.size());
  check(withMapper(self, [&](Mapper& mapper) {
    return mapper.integrate(sensorPoints(view, std::nullopt, intensity, self.point_staging),
                            sensor_to_world);
  }));
}

std::vector<TimedPose> poseTable(const py::array& pose_times, const py::array& poses) {
  if (poses.ndim() != 3 || poses.shape(1) != 4 || poses.shape(2) != 4) {
    raiseInvalid("pose_at: the poses must be an (M, 4, 4) array");
  }
  const std::size_t count = static_cast<std::size_t>(poses.shape(0));
  const ValuesView times(pose_times, "pose_at's times", count);
  std::vector<TimedPose> table(count);
  for (std::size_t k = 0; k < count; ++k) {
    const py::array matrix = poses[py::int_(k)];
    table[k].time_s = times[k];
    table[k].sensor_to_world = toIsometry(matrix, "pose_at's poses");
  }
  return table;
}

void integrateDeskewed(MapperHandle& self, const py::array& points, const py::array& times,
                       const py::array& pose_times, const py::array& poses,
                       const std::optional<py::array>& intensities) {
  const Points3View view(points, "points");
  const ValuesView time(times, "times", view.size());
  const std::optional<ValuesView> intensity =
      optionalValues(intensities, "intensities", view.size());
  const std::vector<TimedPose> table = poseTable(pose_times, poses);
  check(withMapper(self, [&](Mapper& mapper) {
    return mapper.integrate(sensorPoints(view, time, intensity, self.point_staging), table);
  }));
}

void integrateRays(MapperHandle& self, const py::array& origins, const py::array& ends,
                   const std::optional<py::array>& intensities,
                   const std::optional<py::array>& no_return) {
  const Points3View from(origins, "origins");
  const Points3View to(ends, "ends");
  if (from.size() != to.size()) {
    raiseInvalid("origins and ends must have the same length (" + std::to_string(from.size()) +
                 " and " + std::to_string(to.size()) + ")");
  }
  const std::optional<ValuesView> intensity = optionalValues(intensities, "intensities", to.size());
  std::optional<FlagsView> flags;
  if (no_return) {
    flags.emplace(*no_return, "no_return", to.size());
  }
  check(withMapper(self, [&](Mapper& mapper) {
    std::vector<WorldRay>& scan = self.ray_staging;
    scan.resize(to.size());
    for (std::size_t i = 0; i < scan.size(); ++i) {
      scan[i].origin = from[i];
      scan[i].end = to[i];
      scan[i].intensity = intensity ? static_cast<float>((*intensity)[i]) : 0.0f;
      scan[i].no_return = flags ? (*flags)[i] : false;
    }
    return mapper.integrate(scan);
  }));
}

/// One value per point of an (N, 3) array, computed with the GIL released.
template <class T, class Fn>
py::array_t<T> perPoint(MapperHandle& self, const py::array& points, Fn&& fn) {
  const Points3View view(points, "points");
  py::array_t<T> out(static_cast<py::ssize_t>(view.size()));
  T* values = out.mutable_data();
  withMapper(self, [&](const Mapper& mapper) {
    for (std::size_t i = 0; i < view.size(); ++i) {
      values[i] = fn(mapper, view[i]);
    }
  });
  return out;
}

py::dict countersDict(const MapperCounters& c) {
  py::dict d;
  d["scans"] = c.scans;
  d["rays_in"] = c.rays_in;
  d["rays_integrated"] = c.rays_integrated;
  d["rays_invalid"] = c.rays_invalid;
  d["rays_too_short"] = c.rays_too_short;
  d["rays_out_of_bounds"] = c.rays_out_of_bounds;
  d["rays_clipped"] = c.rays_clipped;
  d["rays_no_return"] = c.rays_no_return;
  d["points_no_pose"] = c.points_no_pose;
  d["depth_no_depth"] = c.depth_no_depth;
  d["batches"] = c.batches;
  d["rays_pending"] = c.rays_pending;
  d["rays_prepared_on_device"] = c.rays_prepared_on_device;
  d["points_deskewed_on_device"] = c.points_deskewed_on_device;
  return d;
}

/// A recording's scan in the library's own layout: integrated as it is.
void integrateScan(MapperHandle& self, const py::object& rays) {
  const ScanRays& scan = scanRaysOf(rays);
  check(withMapper(self, [&](Mapper& mapper) {
    return mapper.integrate(std::span<const WorldRay>(scan.rays));
  }));
}

/// A bag's cloud in the library's own layout: deskewed by its own pose table, as it is.
void integrateCloud(MapperHandle& self, const py::object& cloud) {
  const RecordedCloud& c = cloudOf(cloud);
  check(withMapper(self, [&](Mapper& mapper) -> Expected<void, Error> {
    if (c.sensor_poses.empty()) {
      return {};  // a cloud without points has no poses either
    }
    return mapper.integrate(std::span<const SensorPoint>(c.points),
                            std::span<const TimedPose>(c.sensor_poses));
  }));
}

void bindIntegration(py::class_<MapperHandle>& c) {
  c.def("integrate_points", &integratePoints, py::arg("points"), py::arg("pose"),
        py::arg("intensities") = py::none(),
        "Sensor-frame points (N, 3) taken at one pose (4 x 4 sensor-to-world).")
      .def("integrate_deskewed", &integrateDeskewed, py::arg("points"), py::arg("times"),
           py::arg("pose_times"), py::arg("poses"), py::arg("intensities") = py::none(),
           "Sensor-frame points (N, 3) with their times (N,), deskewed by a pose table: times "
           "(M,) increasing and sensor-to-world poses (M, 4, 4).")
      .def("integrate_scan", &integrateScan, py::arg("rays"),
           "The rays of a read_recording() scan (Scan.rays), integrated in place.")
      .def("integrate_cloud", &integrateCloud, py::arg("cloud"),
           "The points of a read_clouds() cloud (Cloud.cloud) deskewed by its poses, in place.")
      .def("integrate_rays", &integrateRays, py::arg("origins"), py::arg("ends"),
           py::arg("intensities") = py::none(), py::arg("no_return") = py::none(),
           "World-frame rays: origins (N, 3), ends (N, 3); no_return (N,) bool marks rays that "
           "only clear free space.")
      .def(
          "flush",
          [](MapperHandle& self) {
            check(withMapper(self, [](Mapper& mapper) { return mapper.flush(); }));
          },
          "Integrates what waits in the batch; queries then see every ray given so far.")
      .def(
          "move_window",
          [](MapperHandle& self, const std::array<double, 3>& centre) {
            return valueOr(withMapper(self, [&](Mapper& mapper) {
              return mapper.moveWindow(Eigen::Vector3d(centre[0], centre[1], centre[2]));
            }));
          },
          py::arg("centre"), "Centres a rolling window on `centre`; returns the regions recycled.");
}

VoxelState stateNamed(const std::string& name) {
  if (name == "occupied") {
    return VoxelState::kOccupied;
  }
  if (name == "free") {
    return VoxelState::kFree;
  }
  raiseInvalid("state: '" + name + "' is not occupied or free");
}

/// The voxels of a state as an (N, 3) array: their keys, or their centres (metres).
template <class T>
py::array_t<T> voxelsOf(MapperHandle& self, const std::string& state, bool centres) {
  const VoxelState wanted = stateNamed(state);
  const std::vector<VoxelKey> keys =
      valueOr(withMapper(self, [&](const Mapper& mapper) { return mapper.voxels(wanted); }));
  py::array_t<T> out({static_cast<py::ssize_t>(keys.size()), py::ssize_t{3}});
  auto view = out.template mutable_unchecked<2>();
  for (std::size_t i = 0; i < keys.size(); ++i) {
    const Eigen::Vector3d at = centres ? self.mapper.centre(keys[i]) : keys[i].cast<double>();
    for (py::ssize_t axis = 0; axis < 3; ++axis) {
      view(static_cast<py::ssize_t>(i), axis) = static_cast<T>(at[axis]);
    }
  }
  return out;
}

void bindQueries(py::class_<MapperHandle>& c) {
  c.def(
       "voxels",
       [](MapperHandle& self, const std::string& state) {
         return voxelsOf<double>(self, state, true);
       },
       py::arg("state") = "occupied",
       "The centres (N, 3) float64 of every voxel in `state` (occupied or free), metres.")
      .def(
          "voxel_keys",
          [](MapperHandle& self, const std::string& state) {
            return voxelsOf<std::int32_t>(self, state, false);
          },
          py::arg("state") = "occupied", "The keys (N, 3) int32 of every voxel in `state`.");
  c.def(
       "occupancy",
       [](MapperHandle& self, const py::array& points) {
         return perPoint<std::int8_t>(self, points,
                                      [](const Mapper& mapper, const Eigen::Vector3d& p) {
                                        return static_cast<std::int8_t>(mapper.occupancy(p));
                                      });
       },
       py::arg("points"),
       "States (N,) int8 of the voxels holding points (N, 3): 0 unobserved, 1 free, 2 occupied.")
      .def(
          "log_odds",
          [](MapperHandle& self, const py::array& points) {
            return perPoint<float>(self, points,
                                   [](const Mapper& mapper, const Eigen::Vector3d& p) {
                                     const std::optional<VoxelKey> key = mapper.key(p);
                                     const std::optional<float> value =
                                         key ? mapper.voxel(*key).log_odds : std::nullopt;
                                     return value.value_or(std::numeric_limits<float>::quiet_NaN());
                                   });
          },
          py::arg("points"), "Occupancy log-odds (N,) float32; NaN where unobserved.")
      .def(
          "counts",
          [](MapperHandle& self) {
            const MapCounts counts =
                withMapper(self, [](Mapper& mapper) { return mapper.counts(); });
            py::dict d;
            d["regions"] = counts.regions;
            d["voxels_free"] = counts.voxels_free;
            d["voxels_occupied"] = counts.voxels_occupied;
            return d;
          },
          "Voxel counts over the map: regions, voxels_free, voxels_occupied.")
      .def(
          "counters",
          [](MapperHandle& self) {
            return countersDict(
                withMapper(self, [](const Mapper& mapper) { return mapper.counters(); }));
          },
          "What the mapper did so far: rays in, integrated, rejected by reason, batches …")
      .def_property_readonly("map_options",
                             [](MapperHandle& self) { return self.mapper.mapOptions(); })
      .def_property_readonly("backend",
                             [](MapperHandle& self) { return self.mapper.backendName(); })
      .def_property_readonly("fallback_warning",
                             [](MapperHandle& self) { return self.mapper.fallbackWarning(); })
      .def_property_readonly("memory_warning",
                             [](MapperHandle& self) { return self.mapper.memoryWarning(); });
}

/// Mapper.export_ply(path, kind, …): the options a kind does not take stay unset (the library
/// refuses one that is set for another kind, naming its key).
py::dict exportPly(MapperHandle& self, const std::string& path, const std::string& kind,
                   std::optional<double> decay_threshold, std::optional<double> ndt_sigmas,
                   std::optional<double> ndt_min_axis, const std::optional<std::string>& ndt_colour,
                   std::optional<double> tsdf_min_weight) {
  ExportRequest request;
  const std::optional<ExportKind> parsed = exportKindFromName(kind);
  if (!parsed) {
    raiseInvalid("export.mode: '" + kind + "' is not an export kind");
  }
  request.kind = *parsed;
  request.decay_threshold = decay_threshold;
  request.ndt_sigmas = ndt_sigmas;
  request.ndt_min_axis = ndt_min_axis;
  request.tsdf_min_weight = tsdf_min_weight;
  if (ndt_colour) {
    request.ndt_colour = exportColourFromName(*ndt_colour);
    if (!request.ndt_colour) {
      raiseInvalid("export.ndt_colour: '" + *ndt_colour +
                   "' is not height, intensity or permeability");
    }
  }
  const ExportCounts counts =
      valueOr(withMapper(self, [&](Mapper& mapper) { return mapper.exportPly(path, request); }));
  py::dict d;
  d["items"] = counts.items;
  d["vertices"] = counts.vertices;
  return d;
}

}  // namespace

void bindMapper(py::module_& m) {
  py::class_<MapperHandle> c(m, "_Mapper", "raymap::Mapper (use raymap.Mapper).");
  c.def_static(
       "create",
       [](const MapperConfig& config) { return MapperHandle(valueOr(Mapper::create(config))); },
       py::arg("config"))
      .def_static(
          "load",
          [](const std::string& path, const RayOptions& rays, const BackendOptions& backend) {
            return MapperHandle(valueOr(Mapper::load(path, rays, backend)));
          },
          py::arg("path"), py::arg("rays"), py::arg("backend"))
      .def(
          "save",
          [](MapperHandle& self, const std::string& path) {
            check(withMapper(self, [&](Mapper& mapper) { return mapper.save(path); }));
          },
          py::arg("path"), "Writes the map (.rmap, as raymap populate), via a temporary file.")
      .def("export_ply", &exportPly, py::arg("path"), py::arg("kind") = "occupied",
           py::arg("decay_threshold") = py::none(), py::arg("ndt_sigmas") = py::none(),
           py::arg("ndt_min_axis") = py::none(), py::arg("ndt_colour") = py::none(),
           py::arg("tsdf_min_weight") = py::none(),
           "Writes the PLY raymap export writes (points, NDT ellipsoids, a TSDF surface or mesh).");
  bindIntegration(c);
  bindQueries(c);
  addGridQueries(c);
  bindDepth(m, c);
  m.def(
      "_pose_matrix",
      [](const std::array<double, 3>& translation, const std::array<double, 4>& quaternion) {
        return poseMatrix(translation, quaternion, "pose");
      },
      py::arg("translation"), py::arg("quaternion_xyzw"),
      "Internal: (translation, quaternion x y z w) as a 4 x 4 matrix, by the library's pose.");
  m.def(
      "load_config",
      [](const std::string& path, const MapperConfig& base) {
        std::vector<std::string> warnings;
        MapperConfig config = valueOr(mapper::loadMapperConfig(path, base, warnings));
        return std::make_pair(config, warnings);
      },
      py::arg("path"), py::arg("base"),
      "The map: and backend: sections of a YAML file (raymapd's keys) over `base`, and the "
      "warnings about old key names.");
}

}  // namespace raymap::python
