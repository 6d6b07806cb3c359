#include "module_util.h"

#include <regex>

#include <fmt/format.h>

namespace gipsi::python {

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

std::string OneLine(const py::error_already_set& e) {
  std::string what = e.what();
  if (auto end = what.find('\n'); end != std::string::npos) what.resize(end);
  return what;
}

py::dict MeshDict(const Mesh& mesh) {
  py::dict d;
  d["nodes"] = py::array_t<double>({mesh.num_nodes(), Index{3}}, mesh.nodes.data());
  d["tets"] = py::array_t<int>({mesh.num_tets(), Index{4}}, mesh.tets.data());
  d["triangles"] = py::array_t<int>({mesh.num_triangles(), Index{3}}, mesh.triangles.data());
  if (mesh.edge_nodes.cols() > 0) {  // a second-order file's middle nodes
    d["edge_nodes"] =
        py::array_t<double>({mesh.edge_nodes.cols(), Index{3}}, mesh.edge_nodes.data());
    d["edge_node_ends"] =
        py::array_t<int>({mesh.edge_node_ends.cols(), Index{2}}, mesh.edge_node_ends.data());
  }
  py::dict groups;
  for (const MeshGroup& g : mesh.groups)
    groups[py::str(g.name)] =
        py::array_t<int>(static_cast<py::ssize_t>(g.items.size()), g.items.data());
  d["groups"] = groups;
  return d;
}

}  // namespace gipsi::python
