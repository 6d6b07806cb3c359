/// @file
/// The `gipsi` Python module (pybind11; docs/python.md): its classes and functions. Scenes run
/// from Python are in simulation.h, probes recorded in memory in memory_probes.h, object and
/// connector types written in Python in python_types.cc, shared helpers in module_util.h.

#include <pybind11/eval.h>
#include <pybind11/functional.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <regex>
#include <string>
#include <thread>
#include <vector>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <nlohmann/json.hpp>

#include "gipsi/base/error.h"
#include "gipsi/base/json_node.h"
#include "gipsi/base/state.h"
#include "gipsi/base/version.h"
#include "gipsi/core/coordinator.h"
#include "gipsi/core/kernel.h"
#include "gipsi/core/port.h"
#include "gipsi/core/registry.h"
#include "gipsi/core/sim_object.h"
#include "gipsi/geometry/boundary.h"
#include "gipsi/io/builtins.h"
#include "gipsi/io/mesh_io.h"
#include "gipsi/io/outputs.h"
#include "gipsi/io/probes.h"
#include "gipsi/io/scene.h"
#include "gipsi/models/ep/cell_models.h"
#include "gipsi/models/ep/single_cell.h"

#include "module_util.h"
#include "python_types.h"
#include "simulation.h"

namespace py = pybind11;

namespace gipsi::python {
namespace {

/// An object of a simulation (keeps the simulation alive).
struct ObjectHandle {
  std::shared_ptr<Simulation> sim;
  SimObject* object;
};

/// A connector of a simulation (keeps the simulation alive).
struct ConnectorHandle {
  std::shared_ptr<Simulation> sim;
  Connector* connector;
};

const char* AccessName(FieldAccess a) {
  return a == FieldAccess::kRead ? "read" : a == FieldAccess::kWrite ? "write" : "read_write";
}

py::list PortList(const Connector& c) {
  py::list out;
  for (const PortUse& p : c.ports()) {
    py::dict d;
    d["key"] = p.key;
    d["object"] = p.object ? p.object->name() : std::string();
    d["kind"] = p.kind == PortUse::Kind::kField                ? "field"
                : p.kind == PortUse::Kind::kBoundaryConditions ? "boundary_conditions"
                                                               : "capability";
    d["name"] = p.name;
    if (p.kind == PortUse::Kind::kField) {
      d["access"] = AccessName(p.access);
      d["units"] = p.units;
      d["components"] = p.components;
    }
    out.append(d);
  }
  return out;
}

py::dict FieldDict(const SimObject& o, FieldId id) {
  const FieldInfo& f = o.field_info(id);
  py::dict d;
  d["location"] = std::string(ToString(f.location));
  d["components"] = f.components;
  d["count"] = o.FieldCount(id);
  d["units"] = f.units;
  d["access"] = AccessName(f.access);
  d["description"] = f.description;
  d["view"] = o.FieldMemory(id) != nullptr;
  return d;
}

FieldId FindFieldOrRaise(const SimObject& o, const std::string& name) {
  if (auto id = o.TryFindField(name)) return *id;
  std::string known;
  for (const FieldInfo& f : o.fields()) known += (known.empty() ? "" : ", ") + f.name;
  throw py::key_error(fmt::format("object '{}' ({}) has no field '{}'; its fields: {}", o.path(),
                                  o.type_name(), name, known));
}

/// `a` as a gipsi.FieldArray (the same memory) carrying the field's name, units and location.
py::object Annotated(const py::array& a, const SimObject& o, FieldId id) {
  const FieldInfo& f = o.field_info(id);
  py::object out = a.attr("view")(py::module_::import("gipsi").attr("FieldArray"));
  out.attr("field") = f.name;
  out.attr("units") = f.units;
  out.attr("location") = std::string(ToString(f.location));
  return out;
}

/// The field as a new (count, components) array: one copy, straight from the object.
py::object ReadField(const ObjectHandle& h, const std::string& name) {
  h.sim->CheckSameThread("field");
  const SimObject& o = *h.object;
  const FieldId id = FindFieldOrRaise(o, name);
  const FieldInfo& f = o.field_info(id);
  if (!f.readable())
    throw py::value_error(fmt::format("field '{}' of '{}' is write-only", name, o.path()));
  const Index count = o.FieldCount(id);
  py::array_t<double> out(
      {static_cast<py::ssize_t>(count), static_cast<py::ssize_t>(f.components)});
  Eigen::Map<Eigen::MatrixXd> view(out.mutable_data(), f.components, count);
  o.ReadField(id, view);
  return Annotated(out, o, id);
}

/// Writes a field with the checks a connector's port gets: writable, the shape (count,
/// components) (a global field also takes (components,)), finite values.
void WriteField(ObjectHandle& h, const std::string& name,
                const py::array_t<double, py::array::c_style | py::array::forcecast>& values) {
  h.sim->CheckSameThread("set_field");
  SimObject& o = *h.object;
  const FieldId id = FindFieldOrRaise(o, name);
  const FieldInfo& f = o.field_info(id);
  if (!f.writable())
    throw py::value_error(
        fmt::format("field '{}' of '{}' is read-only ({})", name, o.path(), f.description));
  const Index count = o.FieldCount(id);
  const bool global_vector = count == 1 && values.ndim() == 1 && values.shape(0) == f.components;
  const bool full =
      values.ndim() == 2 && values.shape(0) == count && values.shape(1) == f.components;
  if (!global_vector && !full) {
    std::vector<py::ssize_t> shape(values.shape(), values.shape() + values.ndim());
    throw py::value_error(fmt::format(
        "field '{}' of '{}' takes an array of shape ({}, {}) in [{}], got ({}); nothing was "
        "written",
        name, o.path(), count, f.components, f.units, fmt::join(shape, ", ")));
  }
  for (py::ssize_t i = 0; i < values.size(); ++i)
    if (!std::isfinite(values.data()[i]))
      throw py::value_error(fmt::format("field '{}' of '{}': value {} is not finite ({})", name,
                                        o.path(), i, values.data()[i]));
  Eigen::Map<const Eigen::MatrixXd> in(values.data(), f.components, count);
  o.WriteField(id, in);
}

}  // namespace
}  // namespace gipsi::python

PYBIND11_MODULE(gipsi, m) {
  using namespace gipsi;
  using namespace gipsi::python;
  m.doc() = "GiPSi: an open-architecture framework for organ-level and surgical simulation";
  m.attr("__version__") = GIPSI_VERSION_STRING;
  m.attr("plugin_interface") = GIPSI_PLUGIN_INTERFACE;

  static py::exception<InputError> input_error(m, "InputError", PyExc_ValueError);
  input_error.doc() =
      "Bad input (scene, mesh, plugin, checkpoint). Attributes: file, path (the JSON path or "
      "line, '' if none), what (the rest of the message).";
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const InputError& e) {
      const ErrorParts parts = SplitMessage(e.what());
      py::object error = py::handle(input_error.ptr())(e.what());
      error.attr("file") = parts.file;
      error.attr("path") = parts.path;
      error.attr("what") = parts.what;
      PyErr_SetObject(input_error.ptr(), error.ptr());
    }
  });

  py::class_<ObjectHandle>(m, "Object", "An object of a simulation (a view; keeps it alive).")
      .def_property_readonly("name", [](const ObjectHandle& h) { return h.object->name(); })
      .def_property_readonly(
          "type", [](const ObjectHandle& h) { return std::string(h.object->type_name()); })
      .def_property_readonly(
          "fields",
          [](const ObjectHandle& h) {
            py::dict d;
            for (std::size_t i = 0; i < h.object->fields().size(); ++i) {
              const FieldId id = h.object->FindField(h.object->fields()[i].name);
              d[py::str(h.object->fields()[i].name)] = FieldDict(*h.object, id);
            }
            return d;
          },
          "Every declared field: location, components, count, units, access, description.")
      .def_property_readonly(
          "positions",
          [](py::object self) {
            const auto& h = self.cast<const ObjectHandle&>();
            const Points& x = h.object->domain_positions();
            return View(x.data(), x.cols(), 3, self);
          },
          "Current domain node positions, (nodes, 3): a read-only view of the object's state "
          "(no copy), valid while the object lives; it follows the simulation as it runs.")
      .def_property_readonly(
          "rest_positions",
          [](py::object self) {
            const auto& h = self.cast<const ObjectHandle&>();
            const Points& x = h.object->domain().nodes;
            return View(x.data(), x.cols(), 3, self);
          },
          "Rest domain node positions, (nodes, 3), a read-only view.")
      .def_property_readonly(
          "tets",
          [](py::object self) {
            const auto& h = self.cast<const ObjectHandle&>();
            const Tets& t = h.object->domain().tets;
            return View(t.data(), t.cols(), 4, self);
          },
          "Domain tetrahedra, (tets, 4) node indices, a read-only view.")
      .def_property_readonly(
          "impl", [](const ObjectHandle& h) -> py::object { return PythonImpl(*h.object); },
          "For an object type written in Python, the instance its factory returned; else None.")
      .def(
          "view",
          [](py::object self, const std::string& name) {
            const auto& h = self.cast<const ObjectHandle&>();
            const SimObject& o = *h.object;
            const FieldId id = FindFieldOrRaise(o, name);
            const double* memory = o.FieldMemory(id);
            if (memory == nullptr)
              throw py::value_error(
                  fmt::format("field '{}' of '{}' is computed on request, not stored: read it with "
                              "field('{}') (a copy); fields with views: {}",
                              name, o.path(), name, [&] {
                                std::string with;
                                for (const FieldInfo& f : o.fields())
                                  if (o.FieldMemory(o.FindField(f.name)) != nullptr)
                                    with += (with.empty() ? "" : ", ") + f.name;
                                return with.empty() ? std::string("none") : with;
                              }()));
            return Annotated(View(memory, o.FieldCount(id), o.field_info(id).components, self), o,
                             id);
          },
          py::arg("name"),
          "A stored field as a read-only (count, components) view of the object's memory, no "
          "copy: it follows the simulation as it runs (fields[name]['view'] says which "
          "fields are stored). Write with set_field.")
      .def("field", &ReadField, py::arg("name"),
           "The field as a new (count, components) array, in its declared units.")
      .def("set_field", &WriteField, py::arg("name"), py::arg("values"),
           "Writes a writable field (shape (count, components); (components,) for a global "
           "field); checked like a connector's port: access, shape and finite values.");

  py::class_<ConnectorHandle>(m, "Connector",
                              "A connector of a simulation (a view; keeps it alive).")
      .def_property_readonly("name", [](const ConnectorHandle& h) { return h.connector->name(); })
      .def_property_readonly(
          "type", [](const ConnectorHandle& h) { return std::string(h.connector->type_name()); })
      .def_property_readonly(
          "fire_count", [](const ConnectorHandle& h) { return h.connector->fire_count(); },
          "How often it has fired (restored by checkpoints).")
      .def_property_readonly(
          "ports", [](const ConnectorHandle& h) { return PortList(*h.connector); },
          "What it declared it uses: a list of dicts (key, object, kind, name, and for fields "
          "access, units, components), as `gipsi validate` lists them.")
      .def_property_readonly(
          "impl", [](const ConnectorHandle& h) -> py::object { return PythonImpl(*h.connector); },
          "For a connector type written in Python, the instance its factory returned (its "
          "attributes are as fire() left them); else None.");

  py::class_<Simulation, std::shared_ptr<Simulation>>(m, "Simulation",
                                                      "A loaded scene, ready to run.")
      .def_static("from_file", &Simulation::FromFile, py::arg("file"),
                  py::arg("plugins") = std::vector<std::string>{},
                  "Loads a scene file (JSON), with the same checks as `gipsi run`.")
      .def_static("from_dict", &Simulation::FromDict, py::arg("scene"),
                  py::arg("name") = "scene.json", py::arg("base_dir") = ".",
                  py::arg("plugins") = std::vector<std::string>{},
                  "Loads a scene from a dict (the JSON scene format); `name` is used in messages "
                  "and `base_dir` resolves relative mesh and plugin paths.")
      .def_property_readonly("time", [](Simulation& s) { return s.kernel().time(); })
      .def_property_readonly("end_time", &Simulation::end_time)
      .def_property_readonly("macro_dt", [](Simulation& s) { return s.kernel().macro_dt(); })
      .def_property_readonly("macro_steps", [](Simulation& s) { return s.kernel().macro_steps(); })
      .def_property_readonly(
          "objects",
          [](std::shared_ptr<Simulation> s) {
            py::dict d;
            for (const auto& [path, object] : s->kernel().ObjectPaths())
              d[py::str(path)] = ObjectHandle{s, object};
            return d;
          },
          "Every object and aggregate part by its full dotted name.")
      .def(
          "object",
          [](std::shared_ptr<Simulation> s, const std::string& name) {
            return ObjectHandle{s, &s->kernel().FindObject(name)};
          },
          py::arg("name"), "The object called `name` (as in scenes and probes).")
      .def_property_readonly(
          "connectors",
          [](std::shared_ptr<Simulation> s) {
            py::dict d;
            Coordinator& c = s->kernel().coordinator();
            for (std::size_t i = 0; i < c.num_connectors(); ++i)
              d[py::str(c.connector(i).name())] = ConnectorHandle{s, &c.connector(i)};
            return d;
          },
          "The scene's connectors by name (an aggregate's own are inside it).")
      .def(
          "connector",
          [](std::shared_ptr<Simulation> s, const std::string& name) {
            Coordinator& c = s->kernel().coordinator();
            std::string known;
            for (std::size_t i = 0; i < c.num_connectors(); ++i) {
              if (c.connector(i).name() == name) return ConnectorHandle{s, &c.connector(i)};
              known += (known.empty() ? "" : ", ") + c.connector(i).name();
            }
            throw py::key_error(fmt::format("the scene has no connector '{}'; its connectors: {}",
                                            name, known.empty() ? "none" : known));
          },
          py::arg("name"), "The scene's connector called `name`.")
      .def(
          "step",
          [](Simulation& s) {
            return s.Run(s.kernel().time() + s.kernel().macro_dt(), py::none());
          },
          "Runs one macro step; returns the run's outcome as a dict.")
      .def("run", &Simulation::Run, py::arg("until") = py::none(), py::arg("callback") = py::none(),
           "Runs to `until` (default: the scene's end). callback(t) runs after every macro "
           "step; returning False stops the run. Returns a dict: outcome ('completed', "
           "'diverged', 'stopped', 'output_failed'), diagnostic, start_time, end_time, "
           "wall_seconds, macro_steps.")
      .def(
          "schedule",
          [](const std::shared_ptr<Simulation>& s, double time, py::function action,
             const std::string& description) {
            s->Schedule(s, time, std::move(action), description);
          },
          py::arg("time"), py::arg("action"), py::arg("description") = "Python event",
          "Schedules action(sim) at simulated time `time` [s], like a scene's events: it runs "
          "at the start of the first macro step at or after it. An exception it raises stops "
          "the run and is raised by run()/step().")
      .def_property_readonly("fired_events", &Simulation::FiredEvents,
                             "The events fired so far (the scene's and schedule()'s): a list of "
                             "(time, description).")
      .def_property_readonly("probes", &Simulation::probes,
                             "The scene's point and region probes recorded so far: {probe: "
                             "{'time': array, column: array, ...}}.")
      .def("save", &Simulation::Save, "The complete state as bytes (a checkpoint).")
      .def("restore", &Simulation::Restore, py::arg("state"),
           "Restores bytes from save() of the same scene.")
      .def(
          "save_file",
          [](Simulation& s, const std::filesystem::path& f) {
            s.CheckSameThread("save_file");
            s.kernel().WriteCheckpoint(f);
          },
          py::arg("file"), "Writes a checkpoint file (atomic, checksummed; as gipsi run's).")
      .def(
          "restore_file",
          [](Simulation& s, const std::filesystem::path& f) {
            s.CheckIdle("restore_file");
            s.kernel().ReadCheckpoint(f);
          },
          py::arg("file"), "Restores a checkpoint file of the same scene.")
      .def(
          "mesh",
          [](const Simulation& s, const std::string& name) {
            const auto& meshes = s.scene().meshes;
            auto it = meshes.find(name);
            if (it == meshes.end()) {
              std::string known;
              for (const auto& [n, mesh] : meshes) known += (known.empty() ? "" : ", ") + n;
              throw py::key_error(fmt::format("the scene has no mesh '{}'; its meshes: {}", name,
                                              known.empty() ? "none" : known));
            }
            return MeshDict(*it->second);
          },
          py::arg("name"),
          "The scene's mesh called `name` (its \"meshes\" entry, as built) as a dict of arrays, "
          "like read_mesh's.")
      .def("write_outputs", &Simulation::WriteOutputs, py::arg("directory") = py::none(),
           "Writes the scene's VTU/PVD series and probe CSVs while it runs, as gipsi run does.");

  // Python-written types go into the module's dicts `_object_types` and `_connector_types`,
  // which every simulation loaded later adds to its registry (python_types.cc).
  m.attr("_object_types") = py::dict();
  m.attr("_connector_types") = py::dict();
  const auto add_type = [](const char* function, const char* kind, const char* dict, bool built_in,
                           const std::string& type, const py::object& factory,
                           const std::string& description) {
    if (!PyCallable_Check(factory.ptr()))
      throw py::type_error(
          fmt::format("{}: the factory must be callable (name, params)", function));
    if (built_in)
      throw py::value_error(fmt::format("{}: '{}' is a built-in {} type", function, type, kind));
    py::dict types = py::module_::import("gipsi").attr(dict);
    types[py::str(type)] = py::make_tuple(factory, "(Python) " + description);
  };
  m.def(
      "register_object",
      [add_type](const std::string& type, const py::object& factory,
                 const std::string& description) {
        TypeRegistry builtins;
        RegisterBuiltins(builtins);
        add_type("register_object", "object", "_object_types", builtins.objects.Contains(type),
                 type, factory, description);
      },
      py::arg("type"), py::arg("factory"), py::arg("description") = "",
      "Registers an object type written in Python for the simulations loaded after it: "
      "factory(name, params) returns an object with `fields` and step/read/write (e.g. a "
      "gipsi.ObjectBase subclass; see docs/python.md). Registering a name again replaces it; a "
      "built-in type's name is refused.");
  m.def(
      "register_connector",
      [add_type](const std::string& type, const py::object& factory,
                 const std::string& description) {
        TypeRegistry builtins;
        RegisterBuiltins(builtins);
        add_type("register_connector", "connector", "_connector_types",
                 builtins.connectors.Contains(type), type, factory, description);
      },
      py::arg("type"), py::arg("factory"), py::arg("description") = "",
      "Registers a connector type written in Python for the simulations loaded after it: "
      "factory(name, params) returns an object with `ports`, `parameters` and fire(t, values) "
      "(e.g. a gipsi.ConnectorBase subclass; see docs/python.md). Registering a name again "
      "replaces it; a built-in type's name is refused.");
  // Base classes that document the protocols (any object with these attributes will do).
  py::exec(R"py(
import numpy as _numpy


class FieldArray(_numpy.ndarray):
    """A field's values: a NumPy array with the field's name, units and location (node,
    element, boundary_vertex, boundary_face or global) as attributes. Arithmetic on it gives
    plain values of the same class; the attributes describe the field it was read from."""

    def __array_finalize__(self, obj):
        self.field = getattr(obj, "field", None)
        self.units = getattr(obj, "units", None)
        self.location = getattr(obj, "location", None)


class ConnectorBase:
    """Base of connectors written in Python (gipsi.register_connector(type, cls)).

    Built as cls(name, params) from the scene's connector entry (params: its JSON as a dict).
    ports: {key: {"access": "read" | "write" | "read_write", "units": "Pa", "components": 1}};
        each key is a parameter naming "object.field"; units and components ('' and 0: any)
        are checked against the field before the first step, like a built-in's ports.
    parameters: the other keys it accepts (any other key is refused with its JSON path).
    fire(t, values): called at the connector's place in the order; values holds a
        (count, components) array per readable port; returns {key: array} for the ports it
        writes (or None). An exception stops the run with it quoted.
    get_state() -> bytes, set_state(bytes): what outlives a fire, for checkpoints and retries
        (without them, a scene with this connector cannot be checkpointed).
    """
    ports = {}
    parameters = ()

    def __init__(self, name, params):
        self.name = name
        self.params = params

    def fire(self, t, values):
        raise NotImplementedError("a gipsi.ConnectorBase must implement fire(t, values)")


class ObjectBase:
    """Base of object types written in Python (gipsi.register_object(type, cls)).

    Built as cls(name, params). fields: {name: {"units", "access", "components",
    "description"}} (global fields); step(t, dt) advances (returning False or raising fails
    the step); read(name) -> values; write(name, values); get_state()/set_state(bytes) for
    checkpoints and retries.
    """
    fields = {}

    def __init__(self, name, params):
        self.name = name
        self.params = params

    def step(self, t, dt):
        raise NotImplementedError("a gipsi.ObjectBase must implement step(t, dt)")

    def read(self, name):
        raise NotImplementedError("a gipsi.ObjectBase must implement read(name)")

    def write(self, name, values):
        raise NotImplementedError("a gipsi.ObjectBase must implement write(name, values)")
)py",
           m.attr("__dict__"));
  m.def(
      "pace_cell",
      [](const py::dict& cell, double bcl, std::int64_t beats, double dt,
         std::optional<double> stimulus_amplitude, std::optional<double> stimulus_duration,
         std::int64_t record_every, double apd_percent,
         std::optional<py::array_t<double, py::array::c_style | py::array::forcecast>> initial,
         const std::vector<std::string>& plugins) {
        TypeRegistry registry;
        RegisterBuiltins(registry);
        for (const auto& plugin : plugins) registry.LoadPlugin(ResolvePlugin(plugin, "."));
        const JsonDocument doc = JsonDocument::Parse(ToJsonText(cell), "pace_cell");
        const auto model =
            CreateCellModel(registry, JsonNode(doc.root().raw(), "pace_cell", "cell"));
        PacingProtocol protocol;
        protocol.bcl = bcl;
        protocol.beats = beats;
        protocol.dt = dt;
        protocol.stim_amplitude = stimulus_amplitude.value_or(model->default_stimulus().amplitude);
        protocol.stim_duration = stimulus_duration.value_or(model->default_stimulus().duration);
        protocol.record_every = record_every;
        protocol.apd_percent = apd_percent;
        std::vector<double> start;
        if (initial) start.assign(initial->data(), initial->data() + initial->size());
        SingleCellResult r;
        {
          py::gil_scoped_release release;  // pure C++: sweeps in threads run in parallel
          r = PaceSingleCell(*model, protocol, start);
        }
        auto array = [](const std::vector<double>& v) {
          return py::array_t<double>(static_cast<py::ssize_t>(v.size()), v.data());
        };
        auto column = [&](double BeatMetrics::*member) {
          std::vector<double> v;
          for (const BeatMetrics& b : r.beats) v.push_back(b.*member);
          return array(v);
        };
        py::dict beats_out;
        beats_out["start"] = column(&BeatMetrics::start);
        beats_out["rest"] = column(&BeatMetrics::rest);
        beats_out["peak"] = column(&BeatMetrics::peak);
        beats_out["dvdt_max"] = column(&BeatMetrics::dvdt_max);
        beats_out["activation"] = column(&BeatMetrics::activation);
        beats_out["apd"] = column(&BeatMetrics::apd);
        py::dict out;
        out["model"] = std::string(model->type_name());
        out["variant"] = std::string(model->variant());
        out["time"] = array(r.time);
        out["voltage"] = array(r.voltage);
        out["beats"] = beats_out;
        out["final_state"] = array(r.final_state);
        return out;
      },
      py::arg("cell"), py::kw_only(), py::arg("bcl") = 1000.0, py::arg("beats") = 1,
      py::arg("dt") = 0.01, py::arg("stimulus_amplitude") = py::none(),
      py::arg("stimulus_duration") = py::none(), py::arg("record_every") = 10,
      py::arg("apd_percent") = 90.0, py::arg("initial") = py::none(),
      py::arg("plugins") = std::vector<std::string>{},
      "Paces one cell, as `gipsi cell`: cell = {'model': NAME, 'variant': ..., parameter: "
      "value} (the scene's cell model JSON). Times in ms, V in mV, stimulus in uA/uF (default: "
      "the model's). Returns {'model', 'variant', 'time', 'voltage' (every record_every-th "
      "step), 'beats': {'start', 'rest', 'peak', 'dvdt_max', 'activation', 'apd'} (one value "
      "per beat, APD at apd_percent % repolarisation; NaN where undefined), 'final_state'}. "
      "Releases the GIL while it runs.");
  m.def(
      "write_mesh",
      [](const std::filesystem::path& file, const py::dict& mesh) {
        for (const auto& [key, value] : mesh) {
          const std::string k = py::str(key).cast<std::string>();
          if (k != "nodes" && k != "tets" && k != "triangles")
            throw py::key_error(
                fmt::format("write_mesh: unknown key '{}' (expected nodes, tets, triangles)", k));
        }
        // Through the scene loader's checks of a mesh given by its nodes.
        JsonDocument doc = JsonDocument::Parse(ToJsonText(mesh), file.string());
        WriteMesh(file, BuildMesh(doc.root(), "."));
      },
      py::arg("file"), py::arg("mesh"),
      "Writes {'nodes': (N, 3), 'tets': (E, 4) and/or 'triangles': (T, 3)} to a mesh file: "
      ".vtu (tets and triangles), .obj or .stl (triangles); the arrays are checked as a "
      "scene's inline mesh (InputError with the path of a bad value).");
  m.def(
      "read_mesh", [](const std::filesystem::path& file) { return MeshDict(ReadMesh(file)); },
      py::arg("file"),
      "Reads a mesh file (.msh, .vtu, .vtk, .obj, ...) as a dict of arrays: nodes (N, 3), tets "
      "(E, 4), triangles (T, 3), groups {name: item indices}; a second-order file also gives "
      "edge_nodes (K, 3), the edges' middle nodes, and edge_node_ends (K, 2), their edges.");
}
