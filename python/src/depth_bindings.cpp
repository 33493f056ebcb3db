// SPDX-License-Identifier: BSD-3-Clause
// Depth images for Python: raymap::CameraIntrinsics (sensor_msgs/CameraInfo's model) and
// Mapper.integrate_depth(), which hands a NumPy image to Mapper::integrate(DepthImageView, …) in
// place: the rows are read where they are (any row stride), the GIL released meanwhile.
#include <string>

#include "arrays.hpp"
#include "bindings.hpp"
#include "errors.hpp"
#include "raymap/depth_image.hpp"
#include "raymap/mapper.hpp"
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

namespace py = pybind11;

namespace raymap::python {
namespace {

/// `image` as the library's view: (height, width) uint16 millimetres ("16UC1") or float32
/// metres ("32FC1"), either byte order, each row's pixels next to each other.
DepthImageView depthView(const py::array& image) {
  if (image.ndim() != 2) {
    raiseInvalid("depth must be a (height, width) array, not one of " +
                 std::to_string(image.ndim()) + " dimensions");
  }
  const py::dtype type = image.dtype();
  const char kind = type.kind();
  DepthImageView view;
  if (kind == 'u' && type.itemsize() == 2) {
    view.encoding = DepthEncoding::k16UC1;
  } else if (kind == 'f' && type.itemsize() == 4) {
    view.encoding = DepthEncoding::k32FC1;
  } else {
    raiseInvalid("depth must be uint16 (millimetres, 16UC1) or float32 (metres, 32FC1), not " +
                 std::string(py::str(static_cast<const py::object&>(type))));
  }
  const py::ssize_t item = type.itemsize();
  if (image.strides(1) != item || image.strides(0) < item * image.shape(1)) {
    raiseInvalid(
        "depth: each row's pixels must be next to each other in memory, rows in order "
        "(numpy.ascontiguousarray(depth) makes such a copy)");
  }
  view.big_endian = type.byteorder() == '>';
  view.data = image.data();
  view.width = static_cast<std::uint32_t>(image.shape(1));
  view.height = static_cast<std::uint32_t>(image.shape(0));
  view.step = static_cast<std::size_t>(image.strides(0));
  return view;
}

void integrateDepth(MapperHandle& self, const py::array& image, const CameraIntrinsics& camera,
                    const py::array& pose, const DepthOptions& options) {
  const DepthImageView view = depthView(image);
  const Eigen::Isometry3d camera_to_world = toIsometry(pose, "pose");
  check(withMapper(self, [&](Mapper& mapper) {
    return mapper.integrate(view, camera, camera_to_world, options);
  }));
}

const char* distortionName(DistortionModel model) {
  return model == DistortionModel::kPlumbBob ? "plumb_bob" : "none";
}

void bindCamera(py::module_& m) {
  py::class_<CameraIntrinsics>(m, "CameraIntrinsics",
                               "A depth camera as sensor_msgs/CameraInfo describes it: size, K's "
                               "focal lengths and principal point (pixels), plumb_bob "
                               "distortion (k1 k2 p1 p2 k3).")
      .def(py::init<>())
      .def_readwrite("width", &CameraIntrinsics::width)
      .def_readwrite("height", &CameraIntrinsics::height)
      .def_readwrite("fx", &CameraIntrinsics::fx)
      .def_readwrite("fy", &CameraIntrinsics::fy)
      .def_readwrite("cx", &CameraIntrinsics::cx)
      .def_readwrite("cy", &CameraIntrinsics::cy)
      .def_property(
          "distortion", [](const CameraIntrinsics& c) { return distortionName(c.distortion); },
          [](CameraIntrinsics& c, const std::string& name) {
            if (name != "none" && name != "plumb_bob" && name != "rational_polynomial") {
              raiseInvalid("camera.distortion: '" + name +
                           "' is not none, plumb_bob or rational_polynomial");
            }
            c.distortion = name == "none" ? DistortionModel::kNone : DistortionModel::kPlumbBob;
          },
          "none, or plumb_bob (rational_polynomial with its extra terms zero)")
      .def_readwrite("k1", &CameraIntrinsics::k1)
      .def_readwrite("k2", &CameraIntrinsics::k2)
      .def_readwrite("p1", &CameraIntrinsics::p1)
      .def_readwrite("p2", &CameraIntrinsics::p2)
      .def_readwrite("k3", &CameraIntrinsics::k3)
      .def(
          "validate", [](const CameraIntrinsics& c) { check(c.validate()); },
          "Raises InvalidArgument naming the field when the camera cannot be used.");
  py::class_<DepthOptions>(m, "DepthOptions", "How a depth image becomes rays.")
      .def(py::init<>())
      .def_readwrite("downsample", &DepthOptions::downsample)
      .def_readwrite("min_range", &DepthOptions::min_range)
      .def_readwrite("max_range", &DepthOptions::max_range)
      .def_readwrite("invalid_as_free", &DepthOptions::invalid_as_free);
}

}  // namespace

void bindDepth(py::module_& m, py::class_<MapperHandle>& c) {
  bindCamera(m);
  c.def("integrate_depth", &integrateDepth, py::arg("image"), py::arg("camera"), py::arg("pose"),
        py::arg("options"),
        "A depth image (height, width) uint16 mm or float32 m, its camera, the camera-to-world "
        "pose (4 x 4, optical frame) and DepthOptions: one scan.");
}

}  // namespace raymap::python
