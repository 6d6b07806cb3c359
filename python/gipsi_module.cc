/// @file
/// The `gipsi` Python module (pybind11): scenes loaded from files or dicts, stepped and run from
/// Python, objects' positions as NumPy views without a copy, fields read into and written from
/// NumPy arrays (with the checks a connector's ports get), probes recorded in memory as dicts of
/// arrays, checkpoints to bytes and files, and mesh files as arrays. See docs/python.md.

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
#include "gipsi/io/sample_times.h"
#include "gipsi/io/scene.h"
#include "gipsi/models/ep/cell_models.h"
#include "gipsi/models/ep/single_cell.h"

namespace py = pybind11;

namespace gipsi::python {
namespace {

/// The parts of an InputError message "FILE: LOCATION: WHAT" (error.h builds them so; empty
/// parts are left out there). LOCATION is a JSON path ("objects.sheet.density", "probes[2]") or
/// a line ("line 12"); a part is taken as such only if it looks like one.
struct ErrorParts {
  std::string file, path, what;
};

ErrorParts SplitMessage(const std::string& message) {
  static const std::regex file_like(R"([^\s:]+\.[A-Za-z0-9]+)");
  static const std::regex location_like(
      R"([A-Za-z_][\w\-]*(\[\d+\])*(\.[\w\-]+(\[\d+\])*)*|line \d+(, column \d+)?)");
  ErrorParts parts{"", "", message};
  std::string rest = message;
  if (auto colon = rest.find(": ");
      colon != std::string::npos && std::regex_match(rest.substr(0, colon), file_like)) {
    parts.file = rest.substr(0, colon);
    rest = rest.substr(colon + 2);
    if (auto next = rest.find(": ");
        next != std::string::npos && std::regex_match(rest.substr(0, next), location_like)) {
      parts.path = rest.substr(0, next);
      rest = rest.substr(next + 2);
    } else if (rest.starts_with("(document root): ")) {
      rest = rest.substr(17);
    }
    parts.what = rest;
  }
  return parts;
}

/// `value` (a dict) as JSON text: NumPy arrays and scalars become lists and numbers; NaN and
/// infinities are refused (ValueError), anything else not JSON is a TypeError naming its type.
std::string ToJsonText(const py::handle& value) {
  py::cpp_function to_json([](const py::object& v) -> py::object {
    if (py::hasattr(v, "tolist")) return v.attr("tolist")();
    throw py::type_error(
        fmt::format("a {} is not JSON (expected numbers, strings, lists, dicts, NumPy arrays)",
                    py::str(py::type::of(v).attr("__name__")).cast<std::string>()));
  });
  return py::module_::import("json")
      .attr("dumps")(value, py::arg("default") = to_json, py::arg("allow_nan") = false)
      .cast<std::string>();
}

/// Records the scene's probes in memory, at the times their CSVs would get rows
/// (io/probes.cc): point and region probes every `every` on the grid NextSampleTime keeps;
/// line probes at their `at` times, or once at the end of the first run() when they have none.
/// Saved in checkpoints: every probe's next sample time (line probes: the next of their `at`
/// times) and its number of rows.
class MemoryProbes final : public Observer {
 public:
  explicit MemoryProbes(std::vector<Probe> probes) : probes_(std::move(probes)) {
    for (const Probe& p : probes_) {
      Table table;
      const std::string header = p.Header();
      std::size_t start = 0;
      while (start <= header.size()) {
        const std::size_t comma = std::min(header.find(',', start), header.size());
        table.columns.push_back(header.substr(start, comma - start));
        start = comma + 1;
      }
      table.values.resize(table.columns.size());
      tables_.push_back(std::move(table));
    }
  }

  void Observe(const Kernel& kernel, double t) override {
    const double tolerance = 1e-9 * kernel.macro_dt();
    for (std::size_t i = 0; i < probes_.size(); ++i) {
      const Probe& p = probes_[i];
      Table& table = tables_[i];
      if (p.is_line()) {
        const auto due = [&] {
          const auto k = static_cast<std::size_t>(table.next);
          return k < p.at.size() && t + tolerance >= p.at[k];
        };
        if (!due()) continue;
        Record(i, t);
        while (due()) table.next += 1;
        continue;
      }
      if (t + tolerance < table.next) continue;
      Record(i, t);
      if (p.every > 0) table.next = NextSampleTime(table.next, p.every, t + tolerance);
    }
  }
  void Finish(const Kernel& kernel) override {
    for (std::size_t i = 0; i < probes_.size(); ++i)
      if (probes_[i].is_line() && probes_[i].at.empty() && tables_[i].next == 0) {
        Record(i, kernel.time());  // once, at the end of the (first) run
        tables_[i].next = 1;
      }
  }
  void SaveState(StateWriter& out) override {
    out.BeginSection("PythonProbes", 2);
    out.WriteInt(static_cast<std::int64_t>(tables_.size()));
    for (const Table& table : tables_) {
      out.WriteDouble(table.next);
      out.WriteInt(table.rows);
    }
    out.EndSection();
  }
  void RestoreState(StateReader& in) override {
    in.BeginSection("PythonProbes", 2);
    const std::int64_t n = in.ReadInt();
    if (n != static_cast<std::int64_t>(tables_.size()))
      throw InputError(fmt::format("the checkpoint has {} probes recorded in memory, this scene {}",
                                   n, tables_.size()));
    pending_.clear();
    for (std::int64_t i = 0; i < n; ++i) {
      const double next = in.ReadDouble();
      pending_.emplace_back(next, in.ReadInt());
    }
    in.EndSection();
  }
  // Rows after the checkpoint's are dropped (a restore within this simulation goes back in
  // time); rows before it that a fresh simulation never recorded stay missing.
  void CommitRestore() override {
    for (std::size_t i = 0; i < tables_.size(); ++i) {
      Table& table = tables_[i];
      table.next = pending_[i].first;
      if (table.rows > pending_[i].second) {
        const std::size_t keep = static_cast<std::size_t>(pending_[i].second);
        const std::size_t per_row = probes_[i].is_line() ? probes_[i].line.cols() : 1;
        for (auto& column : table.values)
          if (column.size() > keep * per_row) column.resize(keep * per_row);
        if (table.times.size() > keep) table.times.resize(keep);
        table.rows = pending_[i].second;
      }
    }
  }

  /// Every probe's columns as NumPy arrays (copies), by probe name. Point and region probes:
  /// {"time": (rows,), column: (rows,)}. Line probes: {"time": (rows,), "distance", "x", "y",
  /// "z": (points,), column: (rows, points)}.
  [[nodiscard]] py::dict ToDict() const {
    py::dict result;
    for (std::size_t i = 0; i < probes_.size(); ++i) {
      const Table& table = tables_[i];
      py::dict columns;
      if (!probes_[i].is_line()) {
        for (std::size_t c = 0; c < table.columns.size(); ++c)
          columns[py::str(table.columns[c])] = Array(table.values[c]);
      } else {
        const Probe& p = probes_[i];
        const auto points = static_cast<py::ssize_t>(p.line.cols());
        columns["time"] = Array(table.times);
        columns["distance"] = Array(p.distance);
        for (int k = 0; k < 3; ++k) {
          std::vector<double> coordinate(static_cast<std::size_t>(points));
          for (py::ssize_t j = 0; j < points; ++j) coordinate[j] = p.line(k, j);
          columns[py::str(std::string(1, "xyz"[k]))] = Array(coordinate);
        }
        for (std::size_t c = 5; c < table.columns.size(); ++c)
          columns[py::str(table.columns[c])] = py::array_t<double>(
              {static_cast<py::ssize_t>(table.rows), points}, table.values[c].data());
      }
      result[py::str(probes_[i].name)] = columns;
    }
    return result;
  }

 private:
  struct Table {
    std::vector<std::string> columns;
    /// Point and region probes: one value per row and column (time first). Line probes: the
    /// field columns (after time, distance, x, y, z) row after row, one value per point.
    std::vector<std::vector<double>> values;
    std::vector<double> times;  // line probes: the sample times
    double next = 0;            // the next sample time (line probes: index into `at`)
    std::int64_t rows = 0;
  };
  static py::array_t<double> Array(const std::vector<double>& v) {
    return py::array_t<double>(static_cast<py::ssize_t>(v.size()), v.data());
  }
  void Record(std::size_t i, double t) {
    const Probe& p = probes_[i];
    Table& table = tables_[i];
    p.Sample(row_);
    if (!p.is_line()) {
      table.values[0].push_back(t);
      for (std::size_t c = 0; c < row_.size() && c + 1 < table.values.size(); ++c)
        table.values[c + 1].push_back(row_[c]);
    } else {
      // Sample: per point, distance, x, y, z, then the field columns.
      const std::size_t width = table.columns.size() - 1, points = p.line.cols();
      table.times.push_back(t);
      for (std::size_t j = 0; j < points; ++j)
        for (std::size_t c = 5; c < table.columns.size(); ++c)
          table.values[c].push_back(row_[j * width + (c - 1)]);
    }
    ++table.rows;
  }

  std::vector<Probe> probes_;
  std::vector<Table> tables_;
  std::vector<double> row_;
  std::vector<std::pair<double, std::int64_t>> pending_;
};

/// A mesh as a dict of arrays (read_mesh's): nodes, tets, triangles, groups.
py::dict MeshDict(const Mesh& mesh);

/// A Python exception in one line, "Type: message" (pybind11's what() adds the traceback).
std::string OneLine(const py::error_already_set& e) {
  std::string what = e.what();
  if (auto end = what.find('\n'); end != std::string::npos) what.resize(end);
  return what;
}

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
      : SimObject(std::move(name)), type_(std::move(type)), impl_(std::move(impl)) {
    if (domain) {
      BoundarySurface boundary = MakeBoundary(*domain);
      positions_ = domain->nodes;
      SetGeometry(std::move(domain), std::move(boundary));
    } else {
      SetGeometry(std::make_shared<const Mesh>(), BoundarySurface{});
    }
    if (!py::hasattr(impl_, "fields") || !py::isinstance<py::dict>(impl_.attr("fields")))
      throw InputError("its 'fields' attribute must be a dict {name: {units, access, ...}}");
    for (const auto& [key, spec_handle] : impl_.attr("fields").cast<py::dict>()) {
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
  ~PythonObject() override {
    py::gil_scoped_acquire gil;
    impl_ = py::object();
  }
  std::string_view type_name() const override { return type_; }
  /// The Python instance the factory returned.
  [[nodiscard]] const py::object& impl() const { return impl_; }
  /// The rest nodes, or what its `positions()` (if it has one) returned after the last step.
  const Points& domain_positions() const override { return positions_; }
  std::string failure_detail() const override { return detail_; }

  void SaveObjectState(StateWriter& out) const override {
    py::gil_scoped_acquire gil;
    if (!py::hasattr(impl_, "get_state")) SimObject::SaveObjectState(out);  // refuses
    out.BeginSection("PythonObject", 1);
    out.WriteString(Call("get_state").cast<std::string>());
    out.EndSection();
  }
  void RestoreObjectState(StateReader& in) override {
    py::gil_scoped_acquire gil;
    if (!py::hasattr(impl_, "set_state")) SimObject::RestoreObjectState(in);  // refuses
    in.BeginSection("PythonObject", 1);
    const std::string state = in.ReadString();
    in.EndSection();
    Call("set_state", py::bytes(state));
    std::string problem;
    try {
      problem = RefreshPositions();
    } catch (py::error_already_set& e) {
      problem = fmt::format("positions() raised {}", OneLine(e));
    }
    if (!problem.empty())
      throw std::runtime_error(fmt::format("{} '{}': {}", type_, name(), problem));
  }

 protected:
  StepStatus DoStep(double t, double dt) override {
    py::gil_scoped_acquire gil;
    try {
      if (impl_.attr("step")(t, dt).is(py::bool_(false))) {
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
    const auto values =
        py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(Call("read", name));
    if (!values || values.size() != out.size())
      throw std::runtime_error(fmt::format("{} '{}': read('{}') returned {} values, expected {}",
                                           type_, this->name(), name, values ? values.size() : 0,
                                           out.size()));
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
    Call("write", field_info(id).name, values);
  }

 private:
  /// impl.name(args...), a Python exception becoming a C++ one with the object named.
  template <class... Args>
  py::object Call(const char* method, Args&&... args) const {
    try {
      return impl_.attr(method)(std::forward<Args>(args)...);
    } catch (py::error_already_set& e) {
      throw std::runtime_error(
          fmt::format("{} '{}': {}() raised {}", type_, name(), method, OneLine(e)));
    }
  }
  /// Takes the node positions from impl.positions(), if it has a domain and that method (with
  /// the GIL); what is wrong with them, or empty. Throws error_already_set if it raises.
  std::string RefreshPositions() {
    if (positions_.cols() == 0 || !py::hasattr(impl_, "positions")) return {};
    const auto x = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(
        impl_.attr("positions")());
    if (!x || x.ndim() != 2 || x.shape(0) != positions_.cols() || x.shape(1) != 3)
      return fmt::format("positions() must return an array of shape ({}, 3)", positions_.cols());
    for (py::ssize_t i = 0; i < x.size(); ++i)
      if (!std::isfinite(x.data()[i]))
        return fmt::format("positions() returned a non-finite value at node {}: {}", i / 3,
                           x.data()[i]);
    std::copy(x.data(), x.data() + x.size(), positions_.data());
    return {};
  }

  std::string type_;
  py::object impl_;
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
      : Connector(ctx.name), type_(std::move(type)), impl_(std::move(impl)) {
    if (!py::hasattr(impl_, "ports") || !py::isinstance<py::dict>(impl_.attr("ports")))
      ctx.params.Fail(fmt::format(
          "{}: its 'ports' attribute must be a dict {{key: {{access, units, components}}}}",
          type_));
    if (!py::hasattr(impl_, "fire"))
      ctx.params.Fail(fmt::format("{}: it has no fire(t, values) method", type_));
    std::vector<std::string> keys;
    for (const auto& [key_handle, spec_handle] : impl_.attr("ports").cast<py::dict>()) {
      Port port;
      port.key = py::str(key_handle).cast<std::string>();
      const py::dict spec = py::reinterpret_borrow<py::object>(spec_handle).cast<py::dict>();
      const std::string access =
          spec.contains("access") ? py::str(spec["access"]).cast<std::string>() : "read";
      if (access != "read" && access != "write" && access != "read_write")
        ctx.params.Fail(fmt::format("{}: port '{}': access '{}' is not read, write or read_write",
                                    type_, port.key, access));
      port.access = access == "read"    ? FieldAccess::kRead
                    : access == "write" ? FieldAccess::kWrite
                                        : FieldAccess::kReadWrite;
      const std::string units =
          spec.contains("units") ? py::str(spec["units"]).cast<std::string>() : "";
      const int components = spec.contains("components") ? spec["components"].cast<int>() : 0;
      if (!ctx.params.Has(port.key))
        ctx.params.Fail(fmt::format("{} needs \"{}\": \"object.field\" (a port it {})", type_,
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
    if (py::hasattr(impl_, "parameters"))
      for (const auto& k : impl_.attr("parameters")) keys.push_back(py::str(k).cast<std::string>());
    for (const auto& [key, value] : ctx.params.raw().items())
      if (key != "type" && key != "every" && key != "description" &&
          std::find(keys.begin(), keys.end(), key) == keys.end())
        ctx.params.At(key).Fail(fmt::format(
            "{} has no parameter '{}' (its ports: {}; its other parameters, from its "
            "'parameters' attribute: {})",
            type_, key, fmt::join(keys.begin(), keys.begin() + std::ssize(ports_), ", "),
            fmt::join(keys.begin() + std::ssize(ports_), keys.end(), ", ")));
  }
  ~PythonConnector() override {
    py::gil_scoped_acquire gil;
    impl_ = py::object();
  }
  std::string_view type_name() const override { return type_; }
  std::string failure_detail() const override { return detail_; }
  /// The Python instance the factory returned.
  [[nodiscard]] const py::object& impl() const { return impl_; }

  void SaveConnectorState(StateWriter& out) const override {
    py::gil_scoped_acquire gil;
    if (!py::hasattr(impl_, "get_state")) Connector::SaveConnectorState(out);  // refuses
    out.BeginSection("PythonConnector", 1);
    out.WriteString(Call("get_state").cast<std::string>());
    out.EndSection();
  }
  void RestoreConnectorState(StateReader& in) override {
    py::gil_scoped_acquire gil;
    if (!py::hasattr(impl_, "set_state")) Connector::RestoreConnectorState(in);  // refuses
    in.BeginSection("PythonConnector", 1);
    const std::string state = in.ReadString();
    in.EndSection();
    Call("set_state", py::bytes(state));
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
      const py::object result = impl_.attr("fire")(t, values);
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
  template <class... Args>
  py::object Call(const char* method, Args&&... args) const {
    try {
      return impl_.attr(method)(std::forward<Args>(args)...);
    } catch (py::error_already_set& e) {
      throw std::runtime_error(
          fmt::format("{} '{}': {}() raised {}", type_, name(), method, OneLine(e)));
    }
  }

  std::string type_;
  py::object impl_;
  std::vector<Port> ports_;
  std::string detail_;
};

/// Adds the object types registered from Python (the module's `_object_types`) to `registry`.
void RegisterPythonTypes(TypeRegistry& registry) {
  const py::dict types = py::module_::import("gipsi").attr("_object_types");
  for (const auto& [key, entry] : types) {
    const std::string type = py::str(key).cast<std::string>();
    const py::tuple t = py::reinterpret_borrow<py::object>(entry).cast<py::tuple>();
    auto factory = std::make_shared<py::object>(t[0]);
    registry.objects.Register(
        type,
        [type, factory](const ObjectBuildContext& ctx) -> std::unique_ptr<SimObject> {
          py::gil_scoped_acquire gil;
          const py::object params =
              py::module_::import("json").attr("loads")(ctx.params.raw().dump());
          // Its "domain" mesh, if any (an InputError here already names the path).
          const std::shared_ptr<const Mesh> mesh =
              ctx.params.Has("domain") ? ctx.DomainMesh() : nullptr;
          py::object impl;
          try {
            impl = (*factory)(ctx.name, params);
            if (mesh && py::hasattr(impl, "set_domain")) impl.attr("set_domain")(MeshDict(*mesh));
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
        t[1].cast<std::string>());
  }
  const py::dict connector_types = py::module_::import("gipsi").attr("_connector_types");
  for (const auto& [key, entry] : connector_types) {
    const std::string type = py::str(key).cast<std::string>();
    const py::tuple t = py::reinterpret_borrow<py::object>(entry).cast<py::tuple>();
    auto factory = std::make_shared<py::object>(t[0]);
    registry.connectors.Register(
        type,
        [type, factory](const ConnectorBuildContext& ctx) -> std::unique_ptr<Connector> {
          py::gil_scoped_acquire gil;
          const py::object params =
              py::module_::import("json").attr("loads")(ctx.params.raw().dump());
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
        t[1].cast<std::string>());
  }
}

/// A loaded scene with its registry (which must outlive the objects its plugins built).
class Simulation {
 public:
  static std::shared_ptr<Simulation> FromFile(const std::filesystem::path& file,
                                              const std::vector<std::string>& plugins) {
    auto sim = std::shared_ptr<Simulation>(new Simulation(plugins, file.parent_path()));
    sim->scene_ = LoadScene(file, *sim->registry_);
    sim->Attach();
    return sim;
  }
  static std::shared_ptr<Simulation> FromDict(const py::dict& scene, const std::string& name,
                                              const std::filesystem::path& base_dir,
                                              const std::vector<std::string>& plugins) {
    // NumPy arrays and scalars (e.g. a mesh's "nodes" and "tets") go in as JSON arrays and
    // numbers; NaN and infinities are refused here (ValueError) as the JSON reader would.
    const std::string text = ToJsonText(scene);
    auto sim = std::shared_ptr<Simulation>(new Simulation(plugins, base_dir));
    sim->scene_ = LoadSceneFromString(text, name, base_dir, *sim->registry_);
    sim->Attach();
    return sim;
  }

  Kernel& kernel() { return *scene_.kernel; }
  const Scene& scene() const { return scene_; }
  double end_time() const { return scene_.end_time; }
  py::dict probes() const { return probes_->ToDict(); }

  /// Runs to `until` (default: the scene's end). `callback(t)` is called after every macro
  /// step (with the GIL); returning False stops the run there; an exception stops it and is
  /// raised. Ctrl+C stops it too (KeyboardInterrupt).
  /// Refuses `what` while a run is going on, from any thread: the kernel is mid-step (a
  /// callback or an event may not run, restore or schedule).
  void CheckIdle(const char* what) const {
    if (running_)
      throw std::runtime_error(fmt::format(
          "{}: the simulation is running (called from a callback or an event, or another "
          "thread); wait for run() to return",
          what));
  }
  /// Refuses `what` from another thread while a run is going on (a callback or an event of the
  /// running thread may read and write fields and save between macro steps).
  void CheckSameThread(const char* what) const {
    if (running_ && *running_ != std::this_thread::get_id())
      throw std::runtime_error(fmt::format(
          "{}: the simulation is running on another thread; wait for run() to return", what));
  }

  py::dict Run(std::optional<double> until, const py::object& callback) {
    CheckIdle("run");
    if (const std::string& broken = kernel().broken(); !broken.empty())
      throw std::runtime_error(fmt::format(
          "the simulation cannot go on from t = {:.6g} s: {}; restore() a state saved before "
          "(or restore_file() a checkpoint) to continue",
          kernel().time(), broken));
    const double end = until.value_or(scene_.end_time);
    if (!std::isfinite(end))
      throw py::value_error(fmt::format("until must be finite, got {}", end));
    std::optional<py::error_already_set> error;
    Kernel& k = kernel();
    // Without a callback the GIL is taken back only every 0.1 s of wall time (to see Ctrl+C),
    // so another Python thread that holds it does not delay every macro step.
    using Clock = std::chrono::steady_clock;
    auto last_check = Clock::now();
    ProgressFn progress = [&](double t, double) {
      if (callback.is_none()) {
        const auto now = Clock::now();
        if (now - last_check < std::chrono::milliseconds(100)) return;
        last_check = now;
      }
      py::gil_scoped_acquire gil;
      if (error) return;
      try {
        if (PyErr_CheckSignals() != 0) throw py::error_already_set();
        if (!callback.is_none() && callback(t).is(py::bool_(false))) k.RequestStop();
      } catch (py::error_already_set& e) {
        error.emplace(std::move(e));
        k.RequestStop();
      }
    };
    RunResult result;
    {
      running_ = std::this_thread::get_id();
      const std::shared_ptr<void> not_running(nullptr, [this](void*) { running_.reset(); });
      py::gil_scoped_release release;
      result = k.Run(end, progress);
    }
    if (event_error_) {
      py::error_already_set e = std::move(*event_error_);
      event_error_.reset();
      throw e;
    }
    if (error) throw std::move(*error);
    static const char* outcomes[] = {"completed", "diverged", "stopped", "output_failed"};
    py::dict out;
    out["outcome"] = outcomes[static_cast<int>(result.outcome)];
    out["diagnostic"] = result.diagnostic;
    out["start_time"] = result.start_time;
    out["end_time"] = result.end_time;
    out["wall_seconds"] = result.wall_seconds;
    out["macro_steps"] = result.macro_steps;
    return out;
  }

  /// Schedules `action(sim)` at simulated time `time` (with the GIL), as a scene's events: it
  /// runs at the start of the first macro step at or after `time`. An exception it raises stops
  /// the run and is raised by run().
  void Schedule(const std::shared_ptr<Simulation>& self, double time, py::function action,
                const std::string& description) {
    CheckIdle("schedule");  // the kernel's event list may not change while it fires events
    if (!std::isfinite(time))
      throw py::value_error(fmt::format("an event's time must be finite, got {}", time));
    // The kernel holds the action beyond this call; it refers to the simulation weakly, so
    // the simulation can still be freed.
    std::weak_ptr<Simulation> weak = self;
    auto held = std::make_shared<py::function>(std::move(action));
    kernel().ScheduleEvent({time, description, [weak, held](Kernel&) {
                              py::gil_scoped_acquire gil;
                              auto sim = weak.lock();
                              if (!sim) return;
                              try {
                                (*held)(sim);
                              } catch (py::error_already_set& e) {
                                const std::string what = e.what();
                                sim->event_error_.emplace(std::move(e));
                                throw std::runtime_error(
                                    what);  // stops the run: "event at t = ... failed"
                              }
                            }});
  }

  py::list FiredEvents() {
    py::list out;
    for (const auto& [t, description] : kernel().fired_events())
      out.append(py::make_tuple(t, description));
    return out;
  }

  py::bytes Save() {
    CheckSameThread("save");
    StateWriter out;
    kernel().SaveState(out);
    return py::bytes(out.bytes());
  }
  void Restore(const py::bytes& bytes) {
    CheckIdle("restore");
    StateReader in(std::string(bytes), "checkpoint bytes");
    kernel().RestoreState(in);
  }

  /// Attaches the scene's file outputs (VTU/PVD series, probe CSVs) under `directory` (default:
  /// the scene's outputs.directory).
  void WriteOutputs(const std::optional<std::filesystem::path>& directory) {
    CheckIdle("write_outputs");
    AttachOutputs(scene_, directory.value_or(scene_.output_directory));
  }

 private:
  Simulation(const std::vector<std::string>& plugins, const std::filesystem::path& base_dir)
      : registry_(std::make_unique<TypeRegistry>()) {
    RegisterBuiltins(*registry_);
    RegisterPythonTypes(*registry_);
    for (const auto& plugin : plugins) registry_->LoadPlugin(ResolvePlugin(plugin, base_dir));
  }
  void Attach() {
    auto probes = std::make_unique<MemoryProbes>(scene_.probes);
    probes_ = probes.get();
    scene_.kernel->AddObserver(std::move(probes));
  }

  std::unique_ptr<TypeRegistry> registry_;
  Scene scene_;
  std::optional<py::error_already_set> event_error_;  // raised by the Run it stopped
  std::optional<std::thread::id> running_;            // the thread in Run, while it runs
  MemoryProbes* probes_ = nullptr;
};

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
  throw py::key_error(fmt::format("object '{}' ({}) has no field '{}'; its fields: {}", o.name(),
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
    throw py::value_error(fmt::format("field '{}' of '{}' is write-only", name, o.name()));
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
        fmt::format("field '{}' of '{}' is read-only ({})", name, o.name(), f.description));
  const Index count = o.FieldCount(id);
  const bool global_vector = count == 1 && values.ndim() == 1 && values.shape(0) == f.components;
  const bool full =
      values.ndim() == 2 && values.shape(0) == count && values.shape(1) == f.components;
  if (!global_vector && !full) {
    std::vector<py::ssize_t> shape(values.shape(), values.shape() + values.ndim());
    throw py::value_error(fmt::format(
        "field '{}' of '{}' takes an array of shape ({}, {}) in [{}], got ({}); nothing was "
        "written",
        name, o.name(), count, f.components, f.units, fmt::join(shape, ", ")));
  }
  for (py::ssize_t i = 0; i < values.size(); ++i)
    if (!std::isfinite(values.data()[i]))
      throw py::value_error(fmt::format("field '{}' of '{}': value {} is not finite ({})", name,
                                        o.name(), i, values.data()[i]));
  Eigen::Map<const Eigen::MatrixXd> in(values.data(), f.components, count);
  o.WriteField(id, in);
}

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

py::dict MeshDict(const Mesh& mesh) {
  py::dict d;
  d["nodes"] = py::array_t<double>({mesh.num_nodes(), Index{3}}, mesh.nodes.data());
  d["tets"] = py::array_t<int>({mesh.num_tets(), Index{4}}, mesh.tets.data());
  d["triangles"] = py::array_t<int>({mesh.num_triangles(), Index{3}}, mesh.triangles.data());
  py::dict groups;
  for (const MeshGroup& g : mesh.groups)
    groups[py::str(g.name)] =
        py::array_t<int>(static_cast<py::ssize_t>(g.items.size()), g.items.data());
  d["groups"] = groups;
  return d;
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
          "impl",
          [](const ObjectHandle& h) -> py::object {
            if (auto* p = dynamic_cast<PythonObject*>(h.object)) return p->impl();
            return py::none();
          },
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
                              name, o.name(), name, [&] {
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
          "impl",
          [](const ConnectorHandle& h) -> py::object {
            if (auto* p = dynamic_cast<PythonConnector*>(h.connector)) return p->impl();
            return py::none();
          },
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

  m.attr("_object_types") = py::dict();
  m.def(
      "register_object",
      [](const std::string& type, const py::object& factory, const std::string& description) {
        if (!PyCallable_Check(factory.ptr()))
          throw py::type_error("register_object: the factory must be callable (name, params)");
        TypeRegistry builtins;
        RegisterBuiltins(builtins);
        if (builtins.objects.Contains(type))
          throw py::value_error(
              fmt::format("register_object: '{}' is a built-in object type", type));
        py::dict types = py::module_::import("gipsi").attr("_object_types");
        types[py::str(type)] = py::make_tuple(factory, "(Python) " + description);
      },
      py::arg("type"), py::arg("factory"), py::arg("description") = "",
      "Registers an object type written in Python for the simulations loaded after it: "
      "factory(name, params) returns an object with `fields` and step/read/write (see "
      "docs/python.md). Registering a name again replaces it; a built-in name is refused when a "
      "scene is loaded.");
  m.attr("_connector_types") = py::dict();
  m.def(
      "register_connector",
      [](const std::string& type, const py::object& factory, const std::string& description) {
        if (!PyCallable_Check(factory.ptr()))
          throw py::type_error("register_connector: the factory must be callable (name, params)");
        TypeRegistry builtins;
        RegisterBuiltins(builtins);
        if (builtins.connectors.Contains(type))
          throw py::value_error(
              fmt::format("register_connector: '{}' is a built-in connector type", type));
        py::dict types = py::module_::import("gipsi").attr("_connector_types");
        types[py::str(type)] = py::make_tuple(factory, "(Python) " + description);
      },
      py::arg("type"), py::arg("factory"), py::arg("description") = "",
      "Registers a connector type written in Python for the simulations loaded after it: "
      "factory(name, params) returns an object with `ports`, `parameters` and fire(t, values) "
      "(e.g. a gipsi.ConnectorBase subclass; see docs/python.md). Registering a name again "
      "replaces it.");
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
      "(E, 4), triangles (T, 3), groups {name: item indices}.");
}
