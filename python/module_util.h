#pragma once
/// @file
/// What the parts of the `gipsi` Python module share: InputError messages split into file, JSON
/// path and text; dicts as JSON text; Python exceptions in one line; meshes as dicts of arrays;
/// read-only NumPy views of Eigen data.

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <string>

#include "gipsi/base/math.h"
#include "gipsi/geometry/mesh.h"

namespace gipsi::python {

namespace py = pybind11;

/// The parts of an InputError message "FILE: LOCATION: WHAT" (error.h builds them so; empty
/// parts are left out there). LOCATION is a JSON path ("objects.sheet.density", "probes[2]") or
/// a line ("line 12"); a part is taken as such only if it looks like one.
struct ErrorParts {
  std::string file, path, what;
};
ErrorParts SplitMessage(const std::string& message);

/// `value` (a dict) as JSON text: NumPy arrays and scalars become lists and numbers; NaN and
/// infinities are refused (ValueError), anything else not JSON is a TypeError naming its type.
std::string ToJsonText(const py::handle& value);

/// A Python exception in one line, "Type: message" (pybind11's what() adds the traceback).
std::string OneLine(const py::error_already_set& e);

/// A mesh as a dict of arrays (read_mesh's): nodes, tets, triangles, groups.
py::dict MeshDict(const Mesh& mesh);

/// A read-only (rows, cols) view of column-major Eigen data that keeps `owner` alive.
template <class Scalar>
py::array View(const Scalar* data, Index cols, Index rows_per_col, py::object owner) {
  py::array a(py::dtype::of<Scalar>(),
              {static_cast<py::ssize_t>(cols), static_cast<py::ssize_t>(rows_per_col)},
              {static_cast<py::ssize_t>(rows_per_col * sizeof(Scalar)),
               static_cast<py::ssize_t>(sizeof(Scalar))},
              data, owner);
  py::detail::array_proxy(a.ptr())->flags &= ~py::detail::npy_api::NPY_ARRAY_WRITEABLE_;
  return a;
}

}  // namespace gipsi::python
