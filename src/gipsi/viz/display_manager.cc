#include "gipsi/viz/display_manager.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <fmt/format.h>
#include <fmt/ranges.h>

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

/// Default line width and point diameter [pixels].
constexpr float kDefaultLineWidth = 2.0f, kDefaultPointSize = 6.0f;

/// Line segments of an object: its own (SimObject::DisplaySegments, e.g. a spring network's
/// springs), else the unique edges of the domain's tets (or, without tets, its triangles), as
/// node pairs (lower index first, sorted).
std::vector<std::uint32_t> Segments(const SimObject& object) {
  std::vector<std::pair<std::uint32_t, std::uint32_t>> edges;
  if (const Eigen::Matrix2Xi s = object.DisplaySegments(); s.cols() > 0) {
    GIPSI_CHECK(s.minCoeff() >= 0 && s.maxCoeff() < object.domain_positions().cols(),
                "object '{}': a display segment refers to a node outside [0, {})", object.name(),
                object.domain_positions().cols());
    for (Index k = 0; k < s.cols(); ++k)
      edges.emplace_back(std::uint32_t(s(0, k)), std::uint32_t(s(1, k)));
  } else {
    const Mesh& mesh = object.domain();
    auto add = [&](int a, int b) {
      edges.emplace_back(std::uint32_t(std::min(a, b)), std::uint32_t(std::max(a, b)));
    };
    if (mesh.num_tets() > 0) {
      for (Index e = 0; e < mesh.num_tets(); ++e)
        for (int i = 0; i < 4; ++i)
          for (int j = i + 1; j < 4; ++j) add(mesh.tets(i, e), mesh.tets(j, e));
    } else {
      for (Index e = 0; e < mesh.num_triangles(); ++e)
        for (int i = 0; i < 3; ++i) add(mesh.triangles(i, e), mesh.triangles((i + 1) % 3, e));
    }
    std::sort(edges.begin(), edges.end());
    edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
  }
  std::vector<std::uint32_t> out;
  out.reserve(2 * edges.size());
  for (const auto& [a, b] : edges) out.insert(out.end(), {a, b});
  return out;
}

bool HasOwnSegments(const SimObject& object) { return object.DisplaySegments().cols() > 0; }

}  // namespace

bool DisplayManager::HasDefaultGeometry(const SimObject& object) {
  return object.display().triangles.cols() > 0 || HasOwnSegments(object);
}

DisplayManager::DisplayManager(const SimObject& object, ColorSpec spec)
    : DisplayManager(object, DrawSpec{std::move(spec), std::nullopt, false, true, 0, false}) {}

DisplayManager::DisplayManager(const SimObject& object, DrawSpec spec, std::string name)
    : object_(&object),
      geometry_(&object),
      draw_(std::move(spec)),
      name_(name.empty() ? object.name() : std::move(name)),
      map_(ColorMap::Named("viridis")) {
  const ResolvedDraw resolved = CheckDrawSpec(object, draw_, name_);  // throws for a bad spec
  primitive_ = resolved.primitive;
  if (primitive_ == Primitive::kLines) segments_ = Segments(object);
  map_ = ColorMap::Named(draw_.color.color_map);
  if (!resolved.field) return;
  field_ = resolved.field;
  const FieldInfo& info = object.field_info(*field_);
  location_ = info.location;
  if (location_ == FieldLocation::kElement) {
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
  }
  label_ = FieldLabel(info, draw_.color.component);
  raw_.resize(info.components, object.FieldCount(*field_));
  item_.resize(raw_.cols());
}

void DisplayManager::ComputeValues() {
  const SimObject& object = *object_;
  object.ReadField(*field_, raw_);
  if (draw_.color.component >= 0)
    item_ = raw_.row(draw_.color.component);
  else if (raw_.rows() == 1)  // a scalar is drawn as it is: its "magnitude" is not |value|
    item_ = raw_.row(0);
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
  if (primitive_ != Primitive::kTriangles) {  // drawn on the domain nodes
    values_ = *per_node;
    return;
  }
  const Index num_vertices = display.positions.cols();
  values_.resize(num_vertices);
  if (location_ == FieldLocation::kBoundaryVertex) {
    values_ = item_;
  } else if (display.map) {
    // A display vertex touching an item without data has none (not a blend with the marker).
    const FieldInfo& info = object.field_info(*field_);
    if (info.no_data && location_ == FieldLocation::kNode)
      display.map->ApplyMarked(*per_node, values_, *info.no_data);
    else
      display.map->Apply(*per_node, values_);
  } else {
    const auto& to_node = object.boundary().vertex_to_node;
    for (Index v = 0; v < num_vertices; ++v) values_(v) = (*per_node)(to_node[std::size_t(v)]);
  }
}

void DisplayManager::DrawOn(const SimObject& other) {
  GIPSI_CHECK(other.domain_ptr() == object_->domain_ptr(),
              "object '{}' cannot be drawn on '{}': another domain mesh", name_, other.name());
  geometry_ = &other;
}

void DisplayManager::Fill(SurfaceBuffers& out) {
  const SimObject& object = *object_;
  if (out.object != name_) out.object = name_;
  out.primitive = primitive_;
  out.wireframe = draw_.wireframe && primitive_ == Primitive::kTriangles;
  out.size = draw_.size > 0                     ? draw_.size
             : primitive_ == Primitive::kPoints ? kDefaultPointSize
                                                : kDefaultLineWidth;
  std::size_t num_vertices = 0;
  if (primitive_ == Primitive::kTriangles) {
    const DisplayGeometry& display = object.display();
    if (geometry_ == object_) {
      object.UpdateDisplay();
    } else {  // the display surface on the other object's current node positions
      const Points& nodes = geometry_->domain_positions();
      positions_.resize(3, display.positions.cols());
      if (display.map) {
        display.map->Apply(nodes, positions_);
      } else {
        const auto& to_node = object.boundary().vertex_to_node;
        for (Index v = 0; v < positions_.cols(); ++v)
          positions_.col(v) = nodes.col(to_node[std::size_t(v)]);
      }
    }
    const Points& x = geometry_ == object_ ? display.positions : positions_;
    const Triangles& tris = display.triangles;
    VertexNormals(x, tris, normals_);
    num_vertices = static_cast<std::size_t>(x.cols());
    out.positions.resize(3 * num_vertices);
    out.normals.resize(3 * num_vertices);
    for (std::size_t i = 0; i < 3 * num_vertices; ++i) {
      out.positions[i] = static_cast<float>(x.data()[i]);
      out.normals[i] = static_cast<float>(normals_.data()[i]);
    }
    out.indices.resize(3 * static_cast<std::size_t>(tris.cols()));
    for (std::size_t i = 0; i < out.indices.size(); ++i)
      out.indices[i] = static_cast<std::uint32_t>(tris.data()[i]);
  } else {
    // Lines and points live on the current domain nodes and are drawn unshaded (zero normals).
    const Points& x = geometry_->domain_positions();
    num_vertices = static_cast<std::size_t>(x.cols());
    out.positions.resize(3 * num_vertices);
    out.normals.assign(3 * num_vertices, 0.0f);
    for (std::size_t i = 0; i < 3 * num_vertices; ++i)
      out.positions[i] = static_cast<float>(x.data()[i]);
    if (primitive_ == Primitive::kLines) {
      out.indices.assign(segments_.begin(), segments_.end());
    } else {
      out.indices.resize(num_vertices);
      for (std::size_t i = 0; i < num_vertices; ++i) out.indices[i] = std::uint32_t(i);
    }
  }
  out.colors.resize(3 * num_vertices);

  if (!field_) {
    for (std::size_t v = 0; v < num_vertices; ++v) {
      out.colors[3 * v] = draw_.color.solid.r;
      out.colors[3 * v + 1] = draw_.color.solid.g;
      out.colors[3 * v + 2] = draw_.color.solid.b;
    }
    out.values.clear();
    out.field.clear();
    out.units.clear();
    out.color_map.clear();
    out.range_lo = out.range_hi = 0;
    out.num_no_data = 0;
    return;
  }
  ComputeValues();
  const FieldInfo& info = object.field_info(*field_);
  // The no-data marker is not a value: such vertices are drawn in kNoDataColor, out of the
  // range (scalar fields; a component or magnitude of a vector is a value).
  const bool marked = info.no_data && info.components == 1;
  auto no_data = [&](Index v) { return marked && values_(v) == *info.no_data; };
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  if (draw_.color.range) {
    std::tie(lo, hi) = *draw_.color.range;
  } else {
    for (Index v = 0; v < values_.size(); ++v) {
      if (std::isnan(values_(v)) || no_data(v)) continue;
      lo = std::min(lo, values_(v));
      hi = std::max(hi, values_(v));
    }
    if (!(lo <= hi)) lo = hi = 0;  // no values, or all NaN
  }
  out.values.resize(num_vertices);
  out.num_no_data = 0;
  for (std::size_t v = 0; v < num_vertices; ++v) {
    const double value = values_(Index(v));
    if (no_data(Index(v))) {
      ++out.num_no_data;
      out.values[v] = std::numeric_limits<float>::quiet_NaN();
      std::copy_n(kNoDataColor, 3, out.colors.data() + 3 * v);
      continue;
    }
    out.values[v] = static_cast<float>(value);
    const Rgb c = map_.Map(value, lo, hi);
    out.colors[3 * v] = c.r;
    out.colors[3 * v + 1] = c.g;
    out.colors[3 * v + 2] = c.b;
  }
  if (out.field != label_) out.field = label_;
  if (out.units != info.units) out.units = info.units;
  if (out.color_map != map_.name()) out.color_map = map_.name();
  out.range_lo = lo;
  out.range_hi = hi;
}

SceneDisplay::SceneDisplay(const Kernel& kernel,
                           const std::vector<std::pair<std::string, ColorSpec>>& colors)
    : SceneDisplay(kernel, {}, colors) {}

SceneDisplay::SceneDisplay(const Kernel& kernel,
                           const std::vector<std::pair<const SimObject*, DrawSpec>>& scene_specs,
                           const std::vector<std::pair<std::string, ColorSpec>>& colors) {
  std::vector<const SimObject*> leaves;
  const Coordinator& coordinator = kernel.coordinator();
  for (std::size_t i = 0; i < coordinator.num_objects(); ++i)
    coordinator.object(i).CollectLeaves(leaves);
  std::vector<const SimObject*> named;
  for (const auto& [name, spec] : colors) named.push_back(&kernel.FindObject(name));
  std::size_t solid = 0;
  for (const SimObject* leaf : leaves) {
    auto s = std::find_if(scene_specs.begin(), scene_specs.end(),
                          [&](const auto& p) { return p.first == leaf; });
    const bool asked = s != scene_specs.end();
    if (!asked && !DisplayManager::HasDefaultGeometry(*leaf)) continue;
    DrawSpec draw = asked ? s->second : DrawSpec{};
    auto it = std::find(named.begin(), named.end(), leaf);
    if (it != named.end()) {
      draw.color = colors[std::size_t(it - named.begin())].second;
    } else if (draw.color.field.empty() && !draw.solid_given) {
      if (auto color = DefaultColor(*leaf))
        draw.color = *color;
      else
        draw.color.solid = kPalette[solid++ % std::size(kPalette)];
    }
    managers_.emplace_back(*leaf, std::move(draw), kernel.ObjectPath(*leaf));
  }
  // Objects without mechanics drawn on a mechanical object of the same mesh (the same tissue).
  auto mechanical = [](const SimObject& o) {
    const auto position = o.TryFindField("position");
    return position && o.field_info(*position).location == FieldLocation::kNode &&
           o.domain_positions().cols() == o.domain().num_nodes();
  };
  for (DisplayManager& m : managers_) {
    if (mechanical(m.object()) || m.object().domain().num_nodes() == 0) continue;
    for (DisplayManager& other : managers_) {
      if (&other == &m || !mechanical(other.object()) ||
          other.object().domain_ptr() != m.object().domain_ptr())
        continue;
      // One of the two coincident surfaces is hidden at first: the muscle, unless the scene or
      // the command line chose to draw it and not the electrophysiology.
      auto chosen = [&](const SimObject& o) {
        return std::find(named.begin(), named.end(), &o) != named.end() ||
               std::any_of(scene_specs.begin(), scene_specs.end(),
                           [&](const auto& p) { return p.first == &o; });
      };
      auto hide = [](DisplayManager& d) {
        DrawSpec hidden = d.draw();
        hidden.visible = false;
        d = DisplayManager(d.object(), hidden, d.name());
      };
      if (chosen(other.object()) && !chosen(m.object()))
        hide(m);
      else if (!chosen(other.object()))
        hide(other);
      m.DrawOn(other.object());
      break;
    }
  }
  for (std::size_t i = 0; i < named.size(); ++i)
    if (std::none_of(managers_.begin(), managers_.end(),
                     [&](const DisplayManager& m) { return &m.object() == named[i]; }))
      throw InputError(
          fmt::format("object '{}' has nothing to draw and colour (no display surface or springs; "
                      "its scene \"display\" may ask for \"as\": \"points\")",
                      colors[i].first));
}

std::vector<std::pair<std::string, ColorSpec>> SceneDisplay::Colors() const {
  std::vector<std::pair<std::string, ColorSpec>> colors;
  for (const DisplayManager& m : managers_) colors.emplace_back(m.name(), m.spec());
  return colors;
}

std::vector<bool> SceneDisplay::Hidden() const {
  std::vector<bool> hidden;
  for (const DisplayManager& m : managers_) hidden.push_back(!m.draw().visible);
  return hidden;
}

void SceneDisplay::Fill(double t, FrameBuffers& out) {
  out.time = t;
  out.frame = frames_++;
  out.surfaces.resize(managers_.size());
  for (std::size_t i = 0; i < managers_.size(); ++i) managers_[i].Fill(out.surfaces[i]);
}

bool OffersField(const SimObject& object, FieldId id) {
  const FieldInfo& info = object.field_info(id);
  if (!info.readable()) return false;
  const bool located = info.location == FieldLocation::kNode ||
                       info.location == FieldLocation::kElement ||
                       (info.location == FieldLocation::kBoundaryVertex && !object.display().map);
  if (!located) return false;
  if (!info.writable() || info.name == "position" || info.name == "velocity") return true;
  Eigen::MatrixXd values(info.components, object.FieldCount(id));
  if (values.cols() < 2) return false;
  object.ReadField(id, values);
  return !(values.colwise() - values.col(0)).isZero(0.0);
}

std::vector<std::string> ComponentChoices(int components) {
  if (components <= 1) return {};
  std::vector<std::string> choices{"magnitude"};
  for (int k = 0; k < components; ++k)
    choices.push_back(components == 3 ? std::string(1, "xyz"[k]) : fmt::format("[{}]", k));
  return choices;
}

std::optional<ColorSpec> DefaultColor(const SimObject& object) {
  const auto v = object.TryFindField("V");
  if (!v) return std::nullopt;
  const FieldInfo& info = object.field_info(*v);
  if (!info.readable() || info.location != FieldLocation::kNode || info.components != 1)
    return std::nullopt;
  ColorSpec spec;
  spec.field = std::string("V");  // (moved in: GCC 12 warns falsely on assigning a literal here)
  spec.color_map = std::string("cool-warm");
  return spec;
}

void ApplyGeometryOptions(const Kernel& kernel, const std::vector<std::string>& options,
                          std::string_view option,
                          std::vector<std::pair<const SimObject*, DrawSpec>>& specs) {
  for (const std::string& text : options) {
    const std::size_t colon = text.rfind(':');
    const std::string geometry = colon == std::string::npos ? "" : text.substr(colon + 1);
    if (colon == std::string::npos || colon == 0 ||
        (geometry != "surface" && geometry != "lines" && geometry != "points"))
      ThrowInputError("command line", option,
                      fmt::format("expected OBJECT:surface, OBJECT:lines or OBJECT:points, got "
                                  "'{}'",
                                  text));
    const SimObject* object = nullptr;
    try {
      object = &kernel.FindObject(text.substr(0, colon));
    } catch (const InputError& e) {
      ThrowInputError("command line", option, e.what());
    }
    auto it =
        std::find_if(specs.begin(), specs.end(), [&](const auto& p) { return p.first == object; });
    if (it == specs.end()) it = specs.insert(specs.end(), {object, DrawSpec{}});
    it->second.as = geometry == "surface" ? Primitive::kTriangles
                    : geometry == "lines" ? Primitive::kLines
                                          : Primitive::kPoints;
    try {
      (void)DisplayManager(*object, it->second);
    } catch (const InputError& e) {
      ThrowInputError("command line", option, e.what());
    }
  }
}

void ApplyVisibility(const Kernel& kernel, const std::vector<std::string>& names,
                     const std::vector<std::string>& show, const std::vector<std::string>& hide,
                     std::vector<bool>& hidden) {
  hidden.resize(names.size(), false);
  for (const auto* list : {&show, &hide})
    for (const std::string& name : *list) {
      const char* option = list == &show ? "--show" : "--hide";
      std::string path;
      try {
        path = kernel.ObjectPath(kernel.FindObject(name));
      } catch (const InputError& e) {
        ThrowInputError("command line", option, e.what());
      }
      const auto it = std::find(names.begin(), names.end(), path);
      if (it == names.end())
        ThrowInputError(
            "command line", option,
            fmt::format("object '{}' is not drawn; drawn: {}", path, fmt::join(names, ", ")));
      hidden[std::size_t(it - names.begin())] = list == &hide;
    }
}

}  // namespace gipsi::viz
