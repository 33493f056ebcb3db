// SPDX-License-Identifier: BSD-3-Clause
// Error codes to the exception types raymap/__init__.py registers with _set_error_types().
#include "errors.hpp"

#include <array>
#include <cstddef>

#include "bindings.hpp"
#include <pybind11/pybind11.h>

namespace py = pybind11;

namespace raymap::python {
namespace {

constexpr std::size_t kCodes = static_cast<std::size_t>(ErrorCode::kUnsupported) + 1;

/// One exception type per ErrorCode. Set once at import and never released: the types outlive
/// every call, and must not be decremented after the interpreter is gone.
std::array<PyObject*, kCodes>& errorTypes() {
  static std::array<PyObject*, kCodes> types{};
  return types;
}

PyObject* typeFor(ErrorCode code) {
  PyObject* type = errorTypes()[static_cast<std::size_t>(code)];
  return type != nullptr ? type : PyExc_RuntimeError;  // before raymap/__init__.py set them
}

}  // namespace

void raiseError(const Error& error) {
  PyErr_SetString(typeFor(error.code), error.message.c_str());
  throw py::error_already_set();
}

void raiseInvalid(const std::string& message) {
  raiseError(Error{ErrorCode::kInvalidArgument, message});
}

void bindErrors(py::module_& m) {
  m.def(
      "_set_error_types",
      [](const py::dict& types) {
        for (std::size_t i = 0; i < kCodes; ++i) {
          const char* name = toString(static_cast<ErrorCode>(i));
          if (!types.contains(name)) {
            throw py::key_error(std::string("_set_error_types: no type for ") + name);
          }
          py::object type = types[name];
          errorTypes()[i] = type.release().ptr();  // kept for the life of the process
        }
      },
      "Internal: the exception type of each library error code (raymap/__init__.py).");
}

}  // namespace raymap::python
