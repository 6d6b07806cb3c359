#include "gipsi/io/display_spec.h"

#include <algorithm>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "gipsi/base/error.h"

namespace gipsi {

std::vector<std::string> ColorMapNames() { return {"viridis", "cool-warm", "grey", "rainbow"}; }

void CheckColorMapName(std::string_view name) {
  const std::vector<std::string> names = ColorMapNames();
  if (std::find(names.begin(), names.end(), name) == names.end())
    throw InputError(fmt::format("unknown colour map '{}'{}; expected one of: {}", name,
                                 SuggestClosest(name, names), fmt::join(names, ", ")));
}

DrawSpec ParseDrawSpec(const JsonNode& node, std::initializer_list<std::string_view> known_keys) {
  std::vector<std::string> keys{"color", "as", "wireframe", "visible", "size"};
  for (auto k : known_keys) keys.emplace_back(k);
  node.CheckKeys(keys);
  DrawSpec spec;
  if (auto c = node.Find("color")) {
    spec.color = ParseColorSpec(*c);
    spec.solid_given = c->Has("color");
  }
  if (auto as = node.Find("as")) {
    const std::string s = as->AsChoice({"surface", "lines", "points"});
    spec.as = s == "surface" ? Primitive::kTriangles
              : s == "lines" ? Primitive::kLines
                             : Primitive::kPoints;
  }
  spec.wireframe = node.Bool("wireframe", false);
  spec.visible = node.Bool("visible", true);
  if (auto size = node.Find("size")) {
    const double v = size->AsNumber();
    if (!(v >= 1 && v <= 64)) size->Expected("a line width or point size in pixels, in [1, 64]");
    spec.size = static_cast<float>(v);
  }
  return spec;
}

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
    spec.color_map = m->AsString();
    try {
      CheckColorMapName(spec.color_map);
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
  spec.color_map = std::string(map);
  try {
    CheckColorMapName(spec.color_map);
  } catch (const InputError& e) {
    ThrowInputError("command line", "--map", e.what());
  }
  spec.range = range;
  return {std::string(text.substr(0, colon)), spec};
}

ResolvedDraw CheckDrawSpec(const SimObject& object, const DrawSpec& spec, const std::string& name) {
  ResolvedDraw out;
  const bool own_segments = object.DisplaySegments().cols() > 0;
  if (spec.as) {
    out.primitive = *spec.as;
  } else if (object.display().triangles.cols() == 0 && own_segments) {
    out.primitive = Primitive::kLines;
  }
  auto fail_geometry = [&](const std::string& what) {
    throw InputError(fmt::format("object '{}': display: {}", name, what));
  };
  const Mesh& mesh = object.domain();
  switch (out.primitive) {
    case Primitive::kTriangles:
      if (object.display().triangles.cols() == 0)
        fail_geometry("it has no display surface; draw it \"as\": \"lines\" or \"points\"");
      break;
    case Primitive::kLines:
      if (!own_segments && mesh.num_tets() == 0 && mesh.num_triangles() == 0)
        fail_geometry("it has no springs or mesh edges to draw as lines");
      break;
    case Primitive::kPoints:
      if (object.domain_positions().cols() == 0) fail_geometry("it has no nodes to draw as points");
      break;
  }
  const bool surface = out.primitive == Primitive::kTriangles;
  auto fail = [&](const std::string& what) {
    throw InputError(fmt::format("object '{}': display colour: {}", name, what));
  };
  try {
    CheckColorMapName(spec.color.color_map);
  } catch (const InputError& e) {
    fail(e.what());
  }
  if (spec.color.range && !(spec.color.range->second > spec.color.range->first))
    fail(fmt::format("range [{}, {}] is empty", spec.color.range->first, spec.color.range->second));
  if (spec.color.field.empty()) return out;
  out.field = object.TryFindField(spec.color.field);
  if (!out.field) {
    std::vector<std::string> names;
    for (const FieldInfo& f : object.fields()) names.push_back(f.name);
    fail(fmt::format("no field '{}'{}; its fields are: {}", spec.color.field,
                     SuggestClosest(spec.color.field, names), fmt::join(names, ", ")));
  }
  const FieldInfo& info = object.field_info(*out.field);
  if (!info.readable()) fail(fmt::format("field '{}' cannot be read", info.name));
  if (spec.color.component >= info.components)
    fail(fmt::format("field '{}' has {} component(s); component {} does not exist", info.name,
                     info.components, spec.color.component));
  switch (info.location) {
    case FieldLocation::kNode:
    case FieldLocation::kElement:
      break;
    case FieldLocation::kBoundaryVertex:
      if (!surface)
        fail(
            fmt::format("field '{}' lives on boundary vertices, but the object is drawn as {}; "
                        "colour by a node or element field",
                        info.name, out.primitive == Primitive::kLines ? "lines" : "points"));
      if (object.display().map.has_value())
        fail(
            fmt::format("field '{}' lives on boundary vertices, but the object is drawn with an "
                        "embedded display surface; colour by a node or element field",
                        info.name));
      break;
    default:
      fail(
          fmt::format("field '{}' lives on {}s; colour by a node, element or boundary-vertex "
                      "field",
                      info.name, ToString(info.location)));
  }
  return out;
}

}  // namespace gipsi
