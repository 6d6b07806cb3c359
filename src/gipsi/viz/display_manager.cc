#include "gipsi/viz/display_manager.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <fmt/format.h>

#include "gipsi/base/error.h"
#include "gipsi/geometry/normals.h"

namespace gipsi::viz {
namespace {

/// Solid colours for objects without a colour field, in object order.
constexpr Rgb kPalette[] = {{0.80f, 0.45f, 0.40f},
                            {0.40f, 0.60f, 0.85f},
                            {0.55f, 0.75f, 0.45f},
                            {0.85f, 0.70f, 0.35f},
                            {0.65f, 0.50f, 0.80f}};

std::string FieldLabel(const FieldInfo& info, int component) {
  if (info.components == 1) return info.name;
  if (component < 0) return "|" + info.name + "|";
  static constexpr const char* kAxes[] = {"x", "y", "z"};
  if (info.components == 3) return info.name + " " + kAxes[component];
  return fmt::format("{} [{}]", info.name, component);
}

}  // namespace

ColorSpec ParseColorSpec(const JsonNode& node) {
  node.CheckKeys({"field", "component", "map", "range", "color"});
  ColorSpec spec;
  spec.field = node.String("field", "");
  if (auto c = node.Find("component")) {
    if (c->is_string()) {
      const std::string s = c->AsChoice({"magnitude", "x", "y", "z"});
      spec.component = s == "magnitude" ? -1 : s[0] - 'x';
    } else {
      const auto i = c->AsInt();
      if (i < 0 || i > 8) c->Expected("\"magnitude\", \"x\", \"y\", \"z\" or an integer in [0, 8]");
      spec.component = static_cast<int>(i);
    }
  }
  if (auto m = node.Find("map")) {
    try {
      spec.color_map = ColorMap::Named(m->AsString()).name();
    } catch (const InputError& e) {
      m->Fail(e.what());
    }
  }
  if (auto r = node.Find("range")) {
    auto v = r->AsNumbers();
    if (v.size() != 2 || !(v[1] > v[0])) r->Expected("[lo, hi] with lo < hi");
    spec.range = std::pair{v[0], v[1]};
  }
  if (auto c = node.Find("color")) {
    auto v = c->AsNumbers();
    if (v.size() != 3 || std::any_of(v.begin(), v.end(), [](double x) { return x < 0 || x > 1; }))
      c->Expected("[r, g, b] with components in [0, 1]");
    spec.solid = {static_cast<float>(v[0]), static_cast<float>(v[1]), static_cast<float>(v[2])};
  }
  return spec;
}

std::pair<std::string, ColorSpec> ParseColorOption(std::string_view text, std::string_view map,
                                                   std::optional<std::pair<double, double>> range,
                                                   std::string_view option) {
  const std::size_t colon = text.find(':');
  if (colon == std::string_view::npos || colon == 0 || colon + 1 == text.size())
    ThrowInputError("command line", option,
                    fmt::format("expected OBJECT:FIELD[.COMPONENT], got '{}'", text));
  ColorSpec spec;
  spec.field = std::string(text.substr(colon + 1));
  const std::size_t dot = spec.field.rfind('.');
  if (dot != std::string::npos && dot + 2 == spec.field.size()) {
    const char c = spec.field.back();
    if (c >= 'x' && c <= 'z')
      spec.component = c - 'x';
    else if (c >= '0' && c <= '8')
      spec.component = c - '0';
    else
      ThrowInputError("command line", option,
                      fmt::format("component '{}' of '{}' is not x, y, z or 0 ... 8", c, text));
    spec.field.resize(dot);
  }
  try {
    spec.color_map = ColorMap::Named(map).name();
  } catch (const InputError& e) {
    ThrowInputError("command line", "--map", e.what());
  }
  spec.range = range;
  return {std::string(text.substr(0, colon)), spec};
}

DisplayManager::DisplayManager(const SimObject& object, ColorSpec spec)
    : object_(&object), spec_(std::move(spec)), map_(ColorMap::Named("viridis")) {
  auto fail = [&](const std::string& what) {
    throw InputError(fmt::format("object '{}': display colour: {}", object.name(), what));
  };
  try {
    map_ = ColorMap::Named(spec_.color_map);
  } catch (const InputError& e) {
    fail(e.what());
  }
  if (spec_.range && !(spec_.range->second > spec_.range->first))
    fail(fmt::format("range [{}, {}] is empty", spec_.range->first, spec_.range->second));
  if (spec_.field.empty()) return;
  field_ = object.FindField(spec_.field);  // throws naming the object and its fields
  const FieldInfo& info = object.field_info(*field_);
  if (!info.readable()) fail(fmt::format("field '{}' cannot be read", info.name));
  if (spec_.component >= info.components)
    fail(fmt::format("field '{}' has {} component(s); component {} does not exist", info.name,
                     info.components, spec_.component));
  location_ = info.location;
  const bool embedded = object.display().map.has_value();
  switch (location_) {
    case FieldLocation::kNode:
      break;
    case FieldLocation::kBoundaryVertex:
      if (embedded)
        fail(
            fmt::format("field '{}' lives on boundary vertices, but the object is drawn with an "
                        "embedded display surface; colour by a node or element field",
                        info.name));
      break;
    case FieldLocation::kElement: {
      const Mesh& mesh = object.domain();
      const bool tets = mesh.num_tets() > 0;
      const Index num_elems = tets ? mesh.num_tets() : mesh.num_triangles();
      const int per = tets ? 4 : 3;
      auto node_of = [&](Index e, int k) { return tets ? mesh.tets(k, e) : mesh.triangles(k, e); };
      node_elem_start_.assign(static_cast<std::size_t>(mesh.num_nodes()) + 1, 0);
      for (Index e = 0; e < num_elems; ++e)
        for (int k = 0; k < per; ++k) ++node_elem_start_[std::size_t(node_of(e, k)) + 1];
      for (std::size_t n = 1; n < node_elem_start_.size(); ++n)
        node_elem_start_[n] += node_elem_start_[n - 1];
      node_elems_.resize(std::size_t(node_elem_start_.back()));
      std::vector<int> fill(node_elem_start_.begin(), node_elem_start_.end() - 1);
      for (Index e = 0; e < num_elems; ++e)
        for (int k = 0; k < per; ++k)
          node_elems_[std::size_t(fill[std::size_t(node_of(e, k))]++)] = static_cast<int>(e);
      node_.resize(mesh.num_nodes());
      break;
    }
    default:
      fail(
          fmt::format("field '{}' lives on {}s; colour by a node, element or boundary-vertex "
                      "field",
                      info.name, ToString(location_)));
  }
  label_ = FieldLabel(info, spec_.component);
  raw_.resize(info.components, object.FieldCount(*field_));
  item_.resize(raw_.cols());
}

void DisplayManager::ComputeValues() {
  const SimObject& object = *object_;
  object.ReadField(*field_, raw_);
  if (spec_.component >= 0)
    item_ = raw_.row(spec_.component);
  else
    item_ = raw_.colwise().norm();
  const Eigen::RowVectorXd* per_node = &item_;
  if (location_ == FieldLocation::kElement) {
    for (Index n = 0; n < node_.size(); ++n) {
      const int b = node_elem_start_[std::size_t(n)], e = node_elem_start_[std::size_t(n) + 1];
      double sum = 0;
      for (int k = b; k < e; ++k) sum += item_(node_elems_[std::size_t(k)]);
      node_(n) = e > b ? sum / (e - b) : 0.0;
    }
    per_node = &node_;
  }
  const DisplayGeometry& display = object.display();
  const Index num_vertices = display.positions.cols();
  values_.resize(num_vertices);
  if (location_ == FieldLocation::kBoundaryVertex) {
    values_ = item_;
  } else if (display.map) {
    display.map->Apply(*per_node, values_);
  } else {
    const auto& to_node = object.boundary().vertex_to_node;
    for (Index v = 0; v < num_vertices; ++v) values_(v) = (*per_node)(to_node[std::size_t(v)]);
  }
}

void DisplayManager::Fill(SurfaceBuffers& out) {
  const SimObject& object = *object_;
  object.UpdateDisplay();
  const DisplayGeometry& display = object.display();
  const Points& x = display.positions;
  const Triangles& tris = display.triangles;
  VertexNormals(x, tris, normals_);
  const auto num_vertices = static_cast<std::size_t>(x.cols());
  if (out.object != object.name()) out.object = object.name();
  out.positions.resize(3 * num_vertices);
  out.normals.resize(3 * num_vertices);
  out.colors.resize(3 * num_vertices);
  for (std::size_t i = 0; i < 3 * num_vertices; ++i) {
    out.positions[i] = static_cast<float>(x.data()[i]);
    out.normals[i] = static_cast<float>(normals_.data()[i]);
  }
  out.indices.resize(3 * static_cast<std::size_t>(tris.cols()));
  for (std::size_t i = 0; i < out.indices.size(); ++i)
    out.indices[i] = static_cast<std::uint32_t>(tris.data()[i]);

  if (!field_) {
    for (std::size_t v = 0; v < num_vertices; ++v) {
      out.colors[3 * v] = spec_.solid.r;
      out.colors[3 * v + 1] = spec_.solid.g;
      out.colors[3 * v + 2] = spec_.solid.b;
    }
    out.values.clear();
    out.field.clear();
    out.units.clear();
    out.color_map.clear();
    out.range_lo = out.range_hi = 0;
    return;
  }
  ComputeValues();
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  if (spec_.range) {
    std::tie(lo, hi) = *spec_.range;
  } else {
    for (Index v = 0; v < values_.size(); ++v) {
      if (std::isnan(values_(v))) continue;
      lo = std::min(lo, values_(v));
      hi = std::max(hi, values_(v));
    }
    if (!(lo <= hi)) lo = hi = 0;  // no values, or all NaN
  }
  out.values.resize(num_vertices);
  for (std::size_t v = 0; v < num_vertices; ++v) {
    const double value = values_(Index(v));
    out.values[v] = static_cast<float>(value);
    const Rgb c = map_.Map(value, lo, hi);
    out.colors[3 * v] = c.r;
    out.colors[3 * v + 1] = c.g;
    out.colors[3 * v + 2] = c.b;
  }
  const FieldInfo& info = object.field_info(*field_);
  if (out.field != label_) out.field = label_;
  if (out.units != info.units) out.units = info.units;
  if (out.color_map != map_.name()) out.color_map = map_.name();
  out.range_lo = lo;
  out.range_hi = hi;
}

SceneDisplay::SceneDisplay(const Kernel& kernel,
                           const std::vector<std::pair<std::string, ColorSpec>>& specs) {
  std::vector<const SimObject*> leaves;
  const Coordinator& coordinator = kernel.coordinator();
  for (std::size_t i = 0; i < coordinator.num_objects(); ++i)
    coordinator.object(i).CollectLeaves(leaves);
  std::vector<const SimObject*> named;
  for (const auto& [name, spec] : specs) named.push_back(&kernel.FindObject(name));
  std::size_t solid = 0;
  for (const SimObject* leaf : leaves) {
    if (leaf->display().triangles.cols() == 0) continue;
    auto it = std::find(named.begin(), named.end(), leaf);
    if (it != named.end()) {
      managers_.emplace_back(*leaf, specs[std::size_t(it - named.begin())].second);
    } else {
      ColorSpec spec;
      spec.solid = kPalette[solid++ % std::size(kPalette)];
      managers_.emplace_back(*leaf, spec);
    }
  }
  for (std::size_t i = 0; i < named.size(); ++i)
    if (named[i]->display().triangles.cols() == 0)
      throw InputError(fmt::format("object '{}' has no display surface to colour", specs[i].first));
}

void SceneDisplay::Fill(double t, FrameBuffers& out) {
  out.time = t;
  out.frame = frames_++;
  out.surfaces.resize(managers_.size());
  for (std::size_t i = 0; i < managers_.size(); ++i) managers_[i].Fill(out.surfaces[i]);
}

}  // namespace gipsi::viz
