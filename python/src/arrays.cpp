// SPDX-License-Identifier: BSD-3-Clause
// Shape and dtype checks of the arrays the bindings read; messages name the argument.
#include "arrays.hpp"

#include <cmath>
#include <cstring>
#include <string>

#include "errors.hpp"
#include <Eigen/Geometry>

#include "src/io/trajectory.hpp"

namespace py = pybind11;

namespace raymap::python {
namespace {

/// float32 -> true, float64 -> false; anything else raises naming `what`.
bool isFloat32(const py::array& array, const char* what) {
  const py::dtype type = array.dtype();
  if (type.kind() == 'f' && (type.itemsize() == 4 || type.itemsize() == 8)) {
    return type.itemsize() == 4;
  }
  raiseInvalid(std::string(what) + " must be float32 or float64, not " +
               type.attr("name").cast<std::string>());
}

std::string shapeText(const py::array& array) {
  std::string text = "(";
  for (py::ssize_t d = 0; d < array.ndim(); ++d) {
    text += (d > 0 ? ", " : "") + std::to_string(array.shape(d));
  }
  return text + (array.ndim() == 1 ? ",)" : ")");
}

}  // namespace

Points3View::Points3View(const py::array& array, const char* what) : f32_(isFloat32(array, what)) {
  if (array.ndim() != 2 || array.shape(1) != 3) {
    raiseInvalid(std::string(what) + " must be an (N, 3) array, not " + shapeText(array));
  }
  data_ = static_cast<const char*>(array.data());
  rows_ = static_cast<std::size_t>(array.shape(0));
  row_stride_ = array.strides(0);
  column_stride_ = array.strides(1);
}

ValuesView::ValuesView(const py::array& array, const char* what, std::size_t rows)
    : f32_(isFloat32(array, what)) {
  if (array.ndim() != 1 || static_cast<std::size_t>(array.shape(0)) != rows) {
    raiseInvalid(std::string(what) + " must be an (" + std::to_string(rows) +
                 ",) array (one value a point), not " + shapeText(array));
  }
  data_ = static_cast<const char*>(array.data());
  rows_ = rows;
  stride_ = array.strides(0);
}

FlagsView::FlagsView(const py::array& array, const char* what, std::size_t rows) {
  if (array.dtype().kind() != 'b' || array.ndim() != 1 ||
      static_cast<std::size_t>(array.shape(0)) != rows) {
    raiseInvalid(std::string(what) + " must be an (" + std::to_string(rows) +
                 ",) bool array, not " + shapeText(array) + " " +
                 array.dtype().attr("name").cast<std::string>());
  }
  data_ = static_cast<const char*>(array.data());
  stride_ = array.strides(0);
}

py::array_t<double> poseMatrix(const std::array<double, 3>& translation,
                               const std::array<double, 4>& quaternion_xyzw, const char* what) {
  const Eigen::Vector3d position(translation[0], translation[1], translation[2]);
  const Eigen::Quaterniond q(quaternion_xyzw[3], quaternion_xyzw[0], quaternion_xyzw[1],
                             quaternion_xyzw[2]);
  if (!position.allFinite() || !q.coeffs().allFinite() || q.norm() < 1e-9) {
    raiseInvalid(std::string(what) +
                 ": the translation and quaternion must be finite, and the "
                 "quaternion must have a direction");
  }
  const Eigen::Matrix4d m = io::Pose{position, q.normalized()}.toIsometry().matrix();
  py::array_t<double> out({py::ssize_t{4}, py::ssize_t{4}});
  auto view = out.mutable_unchecked<2>();
  for (py::ssize_t r = 0; r < 4; ++r) {
    for (py::ssize_t c = 0; c < 4; ++c) {
      view(r, c) = m(r, c);
    }
  }
  return out;
}

Eigen::Isometry3d toIsometry(const py::array& matrix, const char* what) {
  const bool f32 = isFloat32(matrix, what);
  if (matrix.ndim() != 2 || matrix.shape(0) != 4 || matrix.shape(1) != 4) {
    raiseInvalid(std::string(what) + " must be a (4, 4) matrix, not " + shapeText(matrix));
  }
  Eigen::Matrix4d m;
  const char* base = static_cast<const char*>(matrix.data());
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 4; ++c) {
      const char* at = base + r * matrix.strides(0) + c * matrix.strides(1);
      m(r, c) = readFloat(at, f32);
    }
  }
  if (!m.allFinite()) {
    raiseInvalid(std::string(what) + " has a non-finite entry");
  }
  if (!m.row(3).isApprox(Eigen::RowVector4d(0, 0, 0, 1), 1e-9)) {
    raiseInvalid(std::string(what) + ": the bottom row must be 0 0 0 1");
  }
  const Eigen::Matrix3d rotation = m.topLeftCorner<3, 3>();
  if (!(rotation * rotation.transpose()).isApprox(Eigen::Matrix3d::Identity(), 1e-6) ||
      rotation.determinant() < 0.0) {
    raiseInvalid(std::string(what) + ": the upper-left 3 x 3 block is not a rotation");
  }
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = rotation;  // the library applies it as its unit quaternion
  pose.translation() = m.topRightCorner<3, 1>();
  return pose;
}

}  // namespace raymap::python
