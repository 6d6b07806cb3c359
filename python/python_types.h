#pragma once
/// @file
/// Object and connector types written in Python (gipsi.register_object,
/// gipsi.register_connector): adapters that the kernel steps and fires like built-ins.

#include <pybind11/pybind11.h>

#include "gipsi/core/connector.h"
#include "gipsi/core/registry.h"
#include "gipsi/core/sim_object.h"

namespace gipsi::python {

namespace py = pybind11;

/// Adds the object and connector types registered from Python (the module's `_object_types`
/// and `_connector_types`) to `registry`. Holds the GIL.
void RegisterPythonTypes(TypeRegistry& registry);

/// The Python instance behind an object or connector of a type written in Python; None for
/// any other.
py::object PythonImpl(const SimObject& object);
py::object PythonImpl(const Connector& connector);

}  // namespace gipsi::python
