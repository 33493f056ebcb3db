// SPDX-License-Identifier: BSD-3-Clause
// NumPy arrays read in place: float32 or float64, any strides (a slice, a transposed view), no
// copy made. The views only point into the arrays: the caller keeps them alive, which a bound
// function's arguments are for the whole call, with or without the GIL.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <initializer_list>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <pybind11/numpy.h>

namespace raymap::python {

/// @brief The float32 (f32) or float64 at `at`, which need not be aligned.
inline double readFloat(const char* at, bool f32) noexcept {
  if (f32) {
    float v;
    std::memcpy(&v, at, sizeof(v));
    return static_cast<double>(v);
  }
  double v;
  std::memcpy(&v, at, sizeof(v));
  return v;
}

/// @brief A read-only view of an (N, 3) float32 or float64 array. Thread-safe to read without the
/// GIL while the array lives.
class Points3View {
 public:
  /// @brief Checks `array` (raises raymap.InvalidArgument naming `what`: "points must be an
  /// (N, 3) array …").
  Points3View(const pybind11::array& array, const char* what);
  std::size_t size() const noexcept { return rows_; }
  Eigen::Vector3d operator[](std::size_t i) const noexcept {
    const char* row = data_ + static_cast<std::ptrdiff_t>(i) * row_stride_;
    return {readFloat(row, f32_), readFloat(row + column_stride_, f32_),
            readFloat(row + 2 * column_stride_, f32_)};
  }

 private:
  const char* data_ = nullptr;
  std::size_t rows_ = 0;
  std::ptrdiff_t row_stride_ = 0;
  std::ptrdiff_t column_stride_ = 0;
  bool f32_ = false;
};

/// @brief A read-only view of an (N,) float32 or float64 array (times, intensities).
class ValuesView {
 public:
  /// @brief Checks `array`: one dimension of `rows` entries (raises naming `what`).
  ValuesView(const pybind11::array& array, const char* what, std::size_t rows);
  std::size_t size() const noexcept { return rows_; }
  double operator[](std::size_t i) const noexcept {
    return readFloat(data_ + static_cast<std::ptrdiff_t>(i) * stride_, f32_);
  }

 private:
  const char* data_ = nullptr;
  std::size_t rows_ = 0;
  std::ptrdiff_t stride_ = 0;
  bool f32_ = false;
};

/// @brief A read-only view of an (N,) bool array (no_return flags).
class FlagsView {
 public:
  FlagsView(const pybind11::array& array, const char* what, std::size_t rows);
  bool operator[](std::size_t i) const noexcept {
    return data_[static_cast<std::ptrdiff_t>(i) * stride_] != 0;
  }

 private:
  const char* data_ = nullptr;
  std::ptrdiff_t stride_ = 0;
};

/// @brief A (4, 4) array as a rigid transform, taken as it is (the library applies the rotation
/// as its unit quaternion). Raises naming `what` for another shape, a non-finite
/// entry, a bottom row other than 0 0 0 1 or a block that is not a rotation (1e-6).
Eigen::Isometry3d toIsometry(const pybind11::array& matrix, const char* what);

/// @brief A translation (metres) and a quaternion in ROS's order (x, y, z, w) as a 4 x 4
/// sensor-to-world matrix, through the library's own pose (io::Pose; the quaternion normalised).
/// Raises naming `what` for a non-finite entry or a quaternion without direction.
pybind11::array_t<double> poseMatrix(const std::array<double, 3>& translation,
                                     const std::array<double, 4>& quaternion_xyzw,
                                     const char* what);

/// @brief A NumPy array over `data` (no copy) that keeps `owner` alive: the layers of a height
/// map or costmap returned to Python. `strides` in bytes.
template <class T>
pybind11::array_t<T> arrayOver(const T* data, std::initializer_list<pybind11::ssize_t> shape,
                               std::initializer_list<pybind11::ssize_t> strides,
                               const pybind11::object& owner) {
  pybind11::array_t<T> array(std::vector<pybind11::ssize_t>(shape),
                             std::vector<pybind11::ssize_t>(strides), data, owner);
  // Read-only: the layers belong to the result object.
  pybind11::detail::array_proxy(array.ptr())->flags &=
      ~pybind11::detail::npy_api::NPY_ARRAY_WRITEABLE_;
  return array;
}

}  // namespace raymap::python
