// SPDX-License-Identifier: BSD-3-Clause
// MapperConfig and its parts as Python classes with the C++ field names (docs/library.md's
// tables): raymap.Mapper(**options) sets them by name (raymap/__init__.py). Enumerations are
// the names the command line and raymapd's YAML use ("ray", "ndt-om", "reverse").
#include <array>
#include <optional>
#include <string>

#include "bindings.hpp"
#include "errors.hpp"
#include "raymap/mapper_config.hpp"
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "src/core/byte_size.hpp"
#include "src/mapper/mapper_conversions.hpp"

namespace py = pybind11;

namespace raymap::python {
namespace {

void bindNdtAndTsdf(py::module_& m) {
  py::class_<NdtOptions>(m, "NdtOptions",
                         "NDT-OM / NDT-TM parameters (map.ndt.*); None: the library's default.")
      .def(py::init<>())
      .def_readwrite("sensor_noise", &NdtOptions::sensor_noise, "range noise (sigma), metres")
      .def_readwrite("regulariser", &NdtOptions::regulariser, "voxel edges, (0, 1]")
      .def_readwrite("sample_threshold", &NdtOptions::sample_threshold)
      .def_readwrite("reinit_probability", &NdtOptions::reinit_probability)
      .def_readwrite("reinit_count", &NdtOptions::reinit_count)
      .def_readwrite("adaptation_rate", &NdtOptions::adaptation_rate)
      .def_readwrite("initial_intensity_variance", &NdtOptions::initial_intensity_variance);
  py::class_<TsdfOptions>(m, "TsdfOptions", "TSDF parameters (map.tsdf.*), metres and rays.")
      .def(py::init<>())
      .def_readwrite("truncation", &TsdfOptions::truncation)
      .def_readwrite("max_weight", &TsdfOptions::max_weight)
      .def_readwrite("dropoff", &TsdfOptions::dropoff);
  py::class_<TierOptions>(m, "TierOptions",
                          "Maps larger than memory: compressed and spilled regions.")
      .def(py::init<>())
      .def_readwrite("enabled", &TierOptions::enabled)
      .def_readwrite("compressed_memory_bytes", &TierOptions::compressed_memory_bytes)
      .def_readwrite("spill_dir", &TierOptions::spill_dir);
}

void bindMapOptions(py::module_& m) {
  py::class_<MapOptions>(m, "MapOptions", "The map: geometry, update rules, memory (map.*).")
      .def(py::init<>())
      .def_readwrite("resolution", &MapOptions::resolution, "voxel edge, metres")
      .def_readwrite("region_voxels", &MapOptions::region_voxels)
      .def_property(
          "semantics",
          [](const MapOptions& o) { return o.semantics == Semantics::kPerScan ? "scan" : "ray"; },
          [](MapOptions& o, const std::string& name) {
            if (name != "ray" && name != "scan") {
              raiseInvalid("map.semantics: '" + name + "' is not ray or scan");
            }
            o.semantics = name == "scan" ? Semantics::kPerScan : Semantics::kPerRay;
          },
          "ray: every ray updates every voxel it crosses; scan: each voxel once per scan")
      .def_property(
          "mode", [](const MapOptions& o) { return mapper::modeName(o); },
          [](MapOptions& o, const std::string& name) { check(mapper::applyModeName(name, o)); },
          "occupancy, ndt-om, ndt-tm, tsdf, decay, or <mode>+decay")
      .def_readwrite("voxel_mean", &MapOptions::voxel_mean)
      .def_readwrite("decay_rate", &MapOptions::decay_rate)
      .def_readwrite("occupancy", &MapOptions::occupancy)
      .def_readwrite("ndt", &MapOptions::ndt)
      .def_readwrite("tsdf", &MapOptions::tsdf)
      .def_readwrite("hit_probability", &MapOptions::hit_probability)
      .def_readwrite("miss_probability", &MapOptions::miss_probability)
      .def_readwrite("clamp_min_probability", &MapOptions::clamp_min_probability)
      .def_readwrite("clamp_max_probability", &MapOptions::clamp_max_probability)
      .def_readwrite("occupied_threshold", &MapOptions::occupied_threshold)
      .def_readwrite("max_memory_bytes", &MapOptions::max_memory_bytes)
      .def_readwrite("tiers", &MapOptions::tiers)
      .def_property(
          "window",
          [](const MapOptions& o) -> std::optional<std::array<int, 3>> {
            if (!o.window) {
              return std::nullopt;
            }
            return std::array<int, 3>{o.window->x(), o.window->y(), o.window->z()};
          },
          [](MapOptions& o, const std::optional<std::array<int, 3>>& regions) {
            o.window.reset();
            if (regions) {
              o.window = Eigen::Vector3i((*regions)[0], (*regions)[1], (*regions)[2]);
            }
          },
          "a rolling window: regions per axis (x, y, z), or None");
}

void bindRayAndBackendOptions(py::module_& m) {
  py::class_<RayOptions>(m, "RayOptions", "Limits applied to every ray (rays.*), metres.")
      .def(py::init<>())
      .def_readwrite("min_range", &RayOptions::min_range)
      .def_readwrite("max_range", &RayOptions::max_range)
      .def_readwrite("max_ray_length", &RayOptions::max_ray_length)
      .def_readwrite("segment_length", &RayOptions::segment_length)
      .def_property(
          "walk",
          [](const RayOptions& o) {
            return o.walk == RayOptions::Walk::kForward   ? "forward"
                   : o.walk == RayOptions::Walk::kReverse ? "reverse"
                                                          : "auto";
          },
          [](RayOptions& o, const std::string& name) {
            if (name != "auto" && name != "forward" && name != "reverse") {
              raiseInvalid("rays.walk: '" + name + "' is not auto, forward or reverse");
            }
            o.walk = name == "forward"   ? RayOptions::Walk::kForward
                     : name == "reverse" ? RayOptions::Walk::kReverse
                                         : RayOptions::Walk::kAuto;
          });
  py::class_<BackendOptions>(m, "BackendOptions", "Where integration runs (backend.*).")
      .def(py::init<>())
      .def_readwrite("name", &BackendOptions::name, "cpu, opencl or cuda")
      .def_readwrite("threads", &BackendOptions::threads)
      .def_readwrite("opencl_platform", &BackendOptions::opencl_platform)
      .def_readwrite("opencl_device", &BackendOptions::opencl_device)
      .def_readwrite("cuda_device", &BackendOptions::cuda_device)
      .def_readwrite("fallback_cpu", &BackendOptions::fallback_cpu)
      .def_readwrite("device_planning", &BackendOptions::device_planning)
      .def_readwrite("gpu_cache_bytes", &BackendOptions::gpu_cache_bytes)
      .def_readwrite("gpu_cache_regions", &BackendOptions::gpu_cache_regions)
      .def_readwrite("gpu_memory", &BackendOptions::gpu_memory)
      .def_readwrite("opencl_span_work", &BackendOptions::opencl_span_work)
      .def_readwrite("batch_rays", &BackendOptions::batch_rays);
}

}  // namespace

void bindConfig(py::module_& m) {
  bindNdtAndTsdf(m);
  bindMapOptions(m);
  bindRayAndBackendOptions(m);
  py::class_<MapperConfig>(m, "MapperConfig", "Everything a Mapper is built from.")
      .def(py::init<>())
      .def_readwrite("map", &MapperConfig::map)
      .def_readwrite("rays", &MapperConfig::rays)
      .def_readwrite("backend", &MapperConfig::backend);
  m.def(
      "parse_byte_size", [](const std::string& text) { return valueOr(parseByteSize(text)); },
      py::arg("text"), "Bytes of a size as the command line writes it: 4GiB, 512MiB, 1000000.");
}

}  // namespace raymap::python
