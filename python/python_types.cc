#include "python_types.h"

#include <pybind11/numpy.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "gipsi/base/error.h"
#include "gipsi/base/json_node.h"
#include "gipsi/base/state.h"
#include "gipsi/core/port.h"
#include "gipsi/geometry/boundary.h"
#include "module_util.h"

namespace gipsi::python {
namespace {

/// What an object or a connector written in Python shares: its type name and instance, calls
/// into the instance that name the owner when they raise, and its get_state()/set_state(bytes)
/// in a checkpoint section. The instance is released with the GIL held.
class PythonInstance {
 public:
  PythonInstance(std::string type, py::object impl)
      : type_(std::move(type)), impl_(std::move(impl)) {}
  PythonInstance(const PythonInstance&) = delete;
  PythonInstance& operator=(const PythonInstance&) = delete;
  ~PythonInstance() {
    py::gil_scoped_acquire gil;
    impl_ = py::object();
  }
  [[nodiscard]] const std::string& type() const { return type_; }
  [[nodiscard]] const py::object& impl() const { return impl_; }
  [[nodiscard]] bool Has(const char* attribute) const { return py::hasattr(impl_, attribute); }
  /// impl.method(args...) (GIL held by the caller); a Python exception becomes a C++ one
  /// naming `owner`.
  template <class... Args>
  py::object Call(std::string_view owner, const char* method, Args&&... args) const {
    try {
      return impl_.attr(method)(std::forward<Args>(args)...);
    } catch (py::error_already_set& e) {
      throw std::runtime_error(
          fmt::format("{} '{}': {}() raised {}", type_, owner, method, OneLine(e)));
    }
  }
  /// get_state()'s bytes in a section `tag` (GIL held by the caller).
  void SaveState(StateWriter& out, const char* tag, std::string_view owner) const {
    out.BeginSection(tag, 1);
    out.WriteString(Call(owner, "get_state").cast<std::string>());
    out.EndSection();
  }
  /// set_state(bytes) from a section `tag` (GIL held by the caller).
  void RestoreState(StateReader& in, const char* tag, std::string_view owner) const {
    in.BeginSection(tag, 1);
    const std::string state = in.ReadString();
    in.EndSection();
    Call(owner, "set_state", py::bytes(state));
  }

 private:
  std::string type_;
  py::object impl_;
};

/// An object type written in Python (gipsi.register_object): a class whose instances declare
/// `fields` ({name: {"units", "access", "components", "description"}}, global fields) and
/// implement step(t, dt), read(name) and write(name, values); get_state()/set_state(bytes) make
/// it checkpointable (and so retry-able). Every call holds the GIL.
class PythonObject final : public SimObject {
 public:
  /// `domain`: the scene's mesh named by the object's "domain" key, or nullptr (then only
  /// global fields may be declared).
  PythonObject(std::string name, std::string type, py::object impl,
               std::shared_ptr<const Mesh> domain)
      : SimObject(std::move(name)), py_(std::move(type), std::move(impl)) {
    if (domain) {
      BoundarySurface boundary = MakeBoundary(*domain);
      positions_ = domain->nodes;
      SetGeometry(std::move(domain), std::move(boundary));
    } else {
      SetGeometry(std::make_shared<const Mesh>(), BoundarySurface{});
    }
    if (!py_.Has("fields") || !py::isinstance<py::dict>(py_.impl().attr("fields")))
      throw InputError("its 'fields' attribute must be a dict {name: {units, access, ...}}");
    for (const auto& [key, spec_handle] : py_.impl().attr("fields").cast<py::dict>()) {
      FieldInfo info;
      info.name = py::str(key).cast<std::string>();
      const py::dict spec = py::reinterpret_borrow<py::object>(spec_handle).cast<py::dict>();
      const std::string location =
          spec.contains("location") ? py::str(spec["location"]).cast<std::string>() : "global";
      if (location == "global") {
        info.location = FieldLocation::kGlobal;
      } else if (location == "node" || location == "element") {
        if (this->domain().num_nodes() == 0)
          throw InputError(fmt::format(
              "field '{}' is a {} field, but the object has no \"domain\" mesh to have {}s",
              info.name, location, location));
        info.location = location == "node" ? FieldLocation::kNode : FieldLocation::kElement;
      } else {
        throw InputError(fmt::format("field '{}': location '{}' is not global, node or element",
                                     info.name, location));
      }
      info.units = spec.contains("units") ? py::str(spec["units"]).cast<std::string>() : "1";
      const std::string access =
          spec.contains("access") ? py::str(spec["access"]).cast<std::string>() : "read";
      if (access != "read" && access != "write" && access != "read_write")
        throw InputError(fmt::format("field '{}': access '{}' is not read, write or read_write",
                                     info.name, access));
      info.access = access == "read"    ? FieldAccess::kRead
                    : access == "write" ? FieldAccess::kWrite
                                        : FieldAccess::kReadWrite;
      info.components = spec.contains("components") ? spec["components"].cast<int>() : 1;
      if (info.components != 1 && info.components != 3 && info.components != 9)
        throw InputError(fmt::format("field '{}': {} components (expected 1, 3 or 9)", info.name,
                                     info.components));
      info.description =
          spec.contains("description") ? py::str(spec["description"]).cast<std::string>() : "";
      DeclareField(std::move(info));
    }
  }
  std::string_view type_name() const override { return py_.type(); }
  /// The Python instance the factory returned.
  [[nodiscard]] const py::object& impl() const { return py_.impl(); }
  /// The rest nodes, or what its `positions()` (if it has one) returned after the last step.
  const Points& domain_positions() const override { return positions_; }
  std::string failure_detail() const override { return detail_; }

  void SaveObjectState(StateWriter& out) const override {
    py::gil_scoped_acquire gil;
    if (!py_.Has("get_state")) SimObject::SaveObjectState(out);  // refuses
    py_.SaveState(out, "PythonObject", name());
  }
  void RestoreObjectState(StateReader& in) override {
    py::gil_scoped_acquire gil;
    if (!py_.Has("set_state")) SimObject::RestoreObjectState(in);  // refuses
    py_.RestoreState(in, "PythonObject", name());
    std::string problem;
    try {
      problem = RefreshPositions();
    } catch (py::error_already_set& e) {
      problem = fmt::format("positions() raised {}", OneLine(e));
    }
    if (!problem.empty())
      throw std::runtime_error(fmt::format("{} '{}': {}", py_.type(), name(), problem));
  }

 protected:
  StepStatus DoStep(double t, double dt) override {
    py::gil_scoped_acquire gil;
    try {
      if (py_.impl().attr("step")(t, dt).is(py::bool_(false))) {
        detail_ = "step() returned False";
        return StepStatus::Failed("the Python object's step failed");
      }
      if (std::string problem = RefreshPositions(); !problem.empty()) {
        detail_ = std::move(problem);
        return StepStatus::Failed("the Python object's positions() failed");
      }
    } catch (py::error_already_set& e) {
      detail_ = fmt::format("step() raised {}", OneLine(e));
      return StepStatus::Failed("the Python object's step raised");
    }
    return StepStatus::Ok();
  }
  void DoReadField(FieldId id, Eigen::Ref<Eigen::MatrixXd> out) const override {
    py::gil_scoped_acquire gil;
    const std::string& name = field_info(id).name;
    const auto values = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(
        py_.Call(this->name(), "read", name));
    if (!values || values.size() != out.size())
      throw std::runtime_error(fmt::format("{} '{}': read('{}') returned {} values, expected {}",
                                           py_.type(), this->name(), name,
                                           values ? values.size() : 0, out.size()));
    std::copy(values.data(), values.data() + values.size(), out.data());
  }
  void DoWriteField(FieldId id, const Eigen::Ref<const Eigen::MatrixXd>& in) override {
    py::gil_scoped_acquire gil;
    // A global field as (components,), as before; node and element fields as (count, components).
    py::array_t<double> values = field_info(id).location == FieldLocation::kGlobal
                                     ? py::array_t<double>(static_cast<py::ssize_t>(in.size()))
                                     : py::array_t<double>({static_cast<py::ssize_t>(in.cols()),
                                                            static_cast<py::ssize_t>(in.rows())});
    std::copy(in.data(), in.data() + in.size(), values.mutable_data());
    py_.Call(name(), "write", field_info(id).name, values);
  }

 private:
  /// Takes the node positions from impl.positions(), if it has a domain and that method (with
  /// the GIL); what is wrong with them, or empty. Throws error_already_set if it raises.
  std::string RefreshPositions() {
    if (positions_.cols() == 0 || !py_.Has("positions")) return {};
    const auto x = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(
        py_.impl().attr("positions")());
    if (!x || x.ndim() != 2 || x.shape(0) != positions_.cols() || x.shape(1) != 3)
      return fmt::format("positions() must return an array of shape ({}, 3)", positions_.cols());
    for (py::ssize_t i = 0; i < x.size(); ++i)
      if (!std::isfinite(x.data()[i]))
        return fmt::format("positions() returned a non-finite value at node {}: {}", i / 3,
                           x.data()[i]);
    std::copy(x.data(), x.data() + x.size(), positions_.data());
    return {};
  }

  PythonInstance py_;
  std::string detail_;
  Points positions_ = Points(3, 0);
};

/// A connector type written in Python (gipsi.register_connector): an instance declares `ports`
/// ({key: {"access", "units", "components"}}, each key a parameter naming "object.field") and
/// `parameters` (its other keys), and implements fire(t, values) → {key: array} for the ports
/// it writes; get_state()/set_state(bytes) make it checkpointable. The ports are declared to
/// the kernel like a built-in connector's (units, access and components checked before the
/// first step), and Fire reads and writes them with the checks of Object.set_field. Every call
/// holds the GIL; a Python exception fails the macro step with the exception quoted.
class PythonConnector final : public Connector {
 public:
  PythonConnector(const ConnectorBuildContext& ctx, std::string type, py::object impl)
      : Connector(ctx.name), py_(std::move(type), std::move(impl)) {
    if (!py_.Has("ports") || !py::isinstance<py::dict>(py_.impl().attr("ports")))
      ctx.params.Fail(fmt::format(
          "{}: its 'ports' attribute must be a dict {{key: {{access, units, components}}}}",
          py_.type()));
    if (!py_.Has("fire"))
      ctx.params.Fail(fmt::format("{}: it has no fire(t, values) method", py_.type()));
    std::vector<std::string> keys;
    for (const auto& [key_handle, spec_handle] : py_.impl().attr("ports").cast<py::dict>()) {
      Port port;
      port.key = py::str(key_handle).cast<std::string>();
      const py::dict spec = py::reinterpret_borrow<py::object>(spec_handle).cast<py::dict>();
      const std::string access =
          spec.contains("access") ? py::str(spec["access"]).cast<std::string>() : "read";
      if (access != "read" && access != "write" && access != "read_write")
        ctx.params.Fail(fmt::format("{}: port '{}': access '{}' is not read, write or read_write",
                                    py_.type(), port.key, access));
      port.access = access == "read"    ? FieldAccess::kRead
                    : access == "write" ? FieldAccess::kWrite
                                        : FieldAccess::kReadWrite;
      const std::string units =
          spec.contains("units") ? py::str(spec["units"]).cast<std::string>() : "";
      const int components = spec.contains("components") ? spec["components"].cast<int>() : 0;
      if (!ctx.params.Has(port.key))
        ctx.params.Fail(fmt::format("{} needs \"{}\": \"object.field\" (a port it {})", py_.type(),
                                    port.key, access == "read" ? "reads" : "writes"));
      auto [object, field] = ctx.ObjectField(port.key);
      port.object = object;
      port.field = field;
      port.count = object->FieldCount(field);
      port.components = object->field_info(field).components;
      port.buffer.resize(port.components, port.count);
      UseField(port.key, *object, object->field_info(field).name, port.access, units, components);
      keys.push_back(port.key);
      ports_.push_back(std::move(port));
    }
    if (py_.Has("parameters"))
      for (const auto& k : py_.impl().attr("parameters"))
        keys.push_back(py::str(k).cast<std::string>());
    for (const auto& [key, value] : ctx.params.raw().items())
      if (key != "type" && key != "every" && key != "description" &&
          std::find(keys.begin(), keys.end(), key) == keys.end())
        ctx.params.At(key).Fail(fmt::format(
            "{} has no parameter '{}' (its ports: {}; its other parameters, from its "
            "'parameters' attribute: {})",
            py_.type(), key, fmt::join(keys.begin(), keys.begin() + std::ssize(ports_), ", "),
            fmt::join(keys.begin() + std::ssize(ports_), keys.end(), ", ")));
  }
  std::string_view type_name() const override { return py_.type(); }
  std::string failure_detail() const override { return detail_; }
  /// The Python instance the factory returned.
  [[nodiscard]] const py::object& impl() const { return py_.impl(); }

  void SaveConnectorState(StateWriter& out) const override {
    py::gil_scoped_acquire gil;
    if (!py_.Has("get_state")) Connector::SaveConnectorState(out);  // refuses
    py_.SaveState(out, "PythonConnector", name());
  }
  void RestoreConnectorState(StateReader& in) override {
    py::gil_scoped_acquire gil;
    if (!py_.Has("set_state")) Connector::RestoreConnectorState(in);  // refuses
    py_.RestoreState(in, "PythonConnector", name());
  }

 protected:
  StepStatus DoFire(double t) override {
    py::gil_scoped_acquire gil;
    detail_.clear();
    try {
      py::dict values;
      for (Port& p : ports_) {
        if (p.access == FieldAccess::kWrite) continue;
        p.object->ReadField(p.field, p.buffer);
        py::array_t<double> a(
            {static_cast<py::ssize_t>(p.count), static_cast<py::ssize_t>(p.components)});
        std::copy(p.buffer.data(), p.buffer.data() + p.buffer.size(), a.mutable_data());
        values[py::str(p.key)] = a;
      }
      const py::object result = py_.impl().attr("fire")(t, values);
      if (result.is_none()) return StepStatus::Ok();
      if (!py::isinstance<py::dict>(result)) {
        detail_ = fmt::format("fire() returned a {}, expected a dict {{port: values}} or None",
                              py::str(py::type::of(result).attr("__name__")).cast<std::string>());
        return StepStatus::Failed("the Python connector's fire() returned something else");
      }
      // Check every written port first, so a bad one writes nothing.
      std::vector<std::pair<Port*, py::array_t<double>>> writes;
      for (const auto& [key_handle, value] : result.cast<py::dict>()) {
        const std::string key = py::str(key_handle).cast<std::string>();
        Port* port = nullptr;
        for (Port& p : ports_)
          if (p.key == key) port = &p;
        if (port == nullptr || port->access == FieldAccess::kRead) {
          detail_ = fmt::format("fire() returned '{}', which is not a port it writes", key);
          return StepStatus::Failed("the Python connector wrote an undeclared port");
        }
        auto a = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(value);
        if (!a || a.size() != port->buffer.size()) {
          detail_ = fmt::format("fire() returned {} values for '{}' ({}), expected {} by {}",
                                a ? a.size() : 0, key, port->object->field_info(port->field).name,
                                port->count, port->components);
          return StepStatus::Failed("the Python connector wrote a field with the wrong shape");
        }
        for (py::ssize_t i = 0; i < a.size(); ++i)
          if (!std::isfinite(a.data()[i])) {
            detail_ = fmt::format("fire() returned a non-finite value for '{}' at {}: {}", key, i,
                                  a.data()[i]);
            return StepStatus::Failed("the Python connector wrote a non-finite value");
          }
        writes.emplace_back(port, std::move(a));
      }
      for (auto& [port, a] : writes) {
        std::copy(a.data(), a.data() + a.size(), port->buffer.data());
        port->object->WriteField(port->field, port->buffer);
      }
    } catch (py::error_already_set& e) {
      detail_ = fmt::format("fire() raised {}", OneLine(e));
      return StepStatus::Failed("the Python connector's fire() raised");
    } catch (const std::exception& e) {  // a Python object's read or write failing
      detail_ = e.what();
      return StepStatus::Failed("the Python connector's field access failed");
    }
    return StepStatus::Ok();
  }

 private:
  struct Port {
    std::string key;
    SimObject* object = nullptr;
    FieldId field;
    FieldAccess access = FieldAccess::kRead;
    Index count = 0;
    int components = 0;
    Eigen::MatrixXd buffer;
  };

  PythonInstance py_;
  std::vector<Port> ports_;
  std::string detail_;
};

}  // namespace

namespace {

/// Calls register_one(type, factory, description) for each entry {type: (factory,
/// description)} of the module's dict `name` (GIL held by the caller).
void ForEachRegistered(const char* name,
                       const std::function<void(const std::string&, std::shared_ptr<py::object>,
                                                const std::string&)>& register_one) {
  const py::dict types = py::module_::import("gipsi").attr(name);
  for (const auto& [key, entry] : types) {
    const py::tuple t = py::reinterpret_borrow<py::object>(entry).cast<py::tuple>();
    register_one(py::str(key).cast<std::string>(), std::make_shared<py::object>(t[0]),
                 t[1].cast<std::string>());
  }
}

/// A scene entry's JSON as a Python dict (GIL held by the caller).
py::object ParamsOf(const JsonNode& params) {
  return py::module_::import("json").attr("loads")(params.raw().dump());
}

}  // namespace

void RegisterPythonTypes(TypeRegistry& registry) {
  ForEachRegistered(
      "_object_types", [&](const std::string& type, std::shared_ptr<py::object> factory,
                           const std::string& description) {
        registry.objects.Register(
            type,
            [type, factory](const ObjectBuildContext& ctx) -> std::unique_ptr<SimObject> {
              py::gil_scoped_acquire gil;
              const py::object params = ParamsOf(ctx.params);
              // Its "domain" mesh, if any (an InputError here already names the path).
              const std::shared_ptr<const Mesh> mesh =
                  ctx.params.Has("domain") ? ctx.DomainMesh() : nullptr;
              py::object impl;
              try {
                impl = (*factory)(ctx.name, params);
                if (mesh && py::hasattr(impl, "set_domain"))
                  impl.attr("set_domain")(MeshDict(*mesh));
              } catch (py::error_already_set& e) {
                ctx.params.Fail(fmt::format("{}: {}", type, OneLine(e)));
              }
              try {
                return std::make_unique<PythonObject>(ctx.name, type, impl, mesh);
              } catch (py::error_already_set& e) {
                ctx.params.Fail(fmt::format("{}: its fields: {}", type, OneLine(e)));
              } catch (const std::exception& e) {  // InputError, or a field spec of the wrong type
                ctx.params.Fail(fmt::format("{}: {}", type, e.what()));
              }
            },
            description);
      });
  ForEachRegistered(
      "_connector_types", [&](const std::string& type, std::shared_ptr<py::object> factory,
                              const std::string& description) {
        registry.connectors.Register(
            type,
            [type, factory](const ConnectorBuildContext& ctx) -> std::unique_ptr<Connector> {
              py::gil_scoped_acquire gil;
              const py::object params = ParamsOf(ctx.params);
              py::object impl;
              try {
                impl = (*factory)(ctx.name, params);
              } catch (py::error_already_set& e) {
                ctx.params.Fail(fmt::format("{}: {}", type, OneLine(e)));
              }
              try {
                return std::make_unique<PythonConnector>(ctx, type, impl);
              } catch (const InputError&) {
                throw;  // from ctx: already names the scene, the path and the problem
              } catch (py::error_already_set& e) {
                ctx.params.Fail(fmt::format("{}: its ports: {}", type, OneLine(e)));
              } catch (const std::exception& e) {
                ctx.params.Fail(fmt::format("{}: {}", type, e.what()));
              }
            },
            description);
      });
}

py::object PythonImpl(const SimObject& object) {
  if (const auto* p = dynamic_cast<const PythonObject*>(&object)) return p->impl();
  return py::none();
}

py::object PythonImpl(const Connector& connector) {
  if (const auto* p = dynamic_cast<const PythonConnector*>(&connector)) return p->impl();
  return py::none();
}

}  // namespace gipsi::python
