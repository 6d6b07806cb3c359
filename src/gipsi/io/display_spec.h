#pragma once
/// @file
/// How a scene asks for an object to be drawn: the "display" keys of an object (colour,
/// geometry, wireframe, visibility) and the command line's colour choice, as plain
/// specifications. The scene loader parses them and checks them against the built objects
/// (CheckDrawSpec), so a bad field or geometry is reported with its JSON path; the display
/// managers of the viz layer (viz/display_manager.h) draw them. Nothing here renders.

#include <cstdint>
#include <initializer_list>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "gipsi/base/export.h"
#include "gipsi/base/json_node.h"
#include "gipsi/core/sim_object.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// An sRGB colour with components in [0, 1].
struct Rgb {
  float r = 0, g = 0, b = 0;
  friend bool operator==(const Rgb&, const Rgb&) = default;
};

/// What an object is drawn as: triangles (its display surface), line segments or points.
enum class Primitive : std::uint8_t { kTriangles, kLines, kPoints };

/// How to colour one object. Plain struct.
struct ColorSpec {
  /// Field to colour by ("" = solid colour). Node, element (averaged to nodes) and, for objects
  /// drawn with their own boundary, boundary-vertex fields.
  std::string field;
  /// Component of a vector or tensor field; -1 = magnitude (Euclidean/Frobenius norm).
  int component = -1;
  std::string color_map = "viridis";
  /// Fixed value range; when absent the range follows the values every frame.
  std::optional<std::pair<double, double>> range;
  Rgb solid{0.80f, 0.45f, 0.40f};  ///< colour when `field` is empty
};

/// How to draw one object: its colour, which geometry (its display surface, its springs or
/// mesh edges as lines, its nodes as points), wireframe, visibility. Plain struct.
struct DrawSpec {
  ColorSpec color;
  /// Triangles: the display surface; lines: the object's own segments (a MassSpring's springs;
  /// SimObject::DisplaySegments), else the unique edges of the domain's tets (or triangles);
  /// points: the domain nodes. Absent: the display surface if the object has one, else its
  /// own segments if it has some, else nothing is drawn.
  std::optional<Primitive> as;
  bool wireframe = false;  ///< draw the surface's triangle edges too
  bool visible = true;     ///< initially shown (the viewer can toggle it)
  /// Line width or point diameter in pixels; 0 = default (2 for lines, 6 for points).
  float size = 0;
  /// The scene gave `color.color` (then no palette colour replaces it).
  bool solid_given = false;
};

/// The colour maps a ColorSpec may name (viz::ColorMap::Named draws them): "viridis",
/// "cool-warm", "grey", "rainbow".
std::vector<std::string> ColorMapNames();

/// Throws InputError ("unknown colour map 'X'; expected one of: ...") unless `name` is one of
/// ColorMapNames().
void CheckColorMapName(std::string_view name);

/// Parses {"field": "displacement", "component": "magnitude"|0|1|2|"x"|"y"|"z",
/// "map": "viridis", "range": [lo, hi], "color": [r, g, b]}; throws InputError naming the path.
ColorSpec ParseColorSpec(const JsonNode& node);

/// Parses the drawing keys of an object's "display" entry (other keys, e.g. "mesh", are the
/// caller's): {"color": <ColorSpec>, "as": "surface"|"lines"|"points", "wireframe": bool,
/// "visible": bool, "size": pixels}. `known_keys` lists the caller's keys, so unknown keys are
/// reported together. Throws InputError naming the path.
DrawSpec ParseDrawSpec(const JsonNode& node, std::initializer_list<std::string_view> known_keys);

/// Parses a command-line colour choice "OBJECT:FIELD" where FIELD may end in ".x", ".y", ".z"
/// (or ".0" ... ".8") for one component (else the magnitude), with colour map `map` and
/// optional fixed `range`. Throws InputError naming `option` (e.g. "--color").
std::pair<std::string, ColorSpec> ParseColorOption(std::string_view text, std::string_view map,
                                                   std::optional<std::pair<double, double>> range,
                                                   std::string_view option);

/// What a DrawSpec resolves to on one object. Plain struct.
struct ResolvedDraw {
  Primitive primitive = Primitive::kTriangles;
  std::optional<FieldId> field;  ///< the colour field; absent for a solid colour
};

/// Checks `spec` against `object` and resolves its geometry and colour field. Throws
/// InputError, naming the object as `name` ("object 'NAME': display: ..." for the geometry,
/// "object 'NAME': display colour: ..." for the colour), for a geometry the object does not
/// have (no display surface, no springs or mesh edges, no nodes), an unknown colour map, an
/// empty range, an unknown or unreadable field, a component out of range, or a field location
/// that cannot be drawn that way.
ResolvedDraw CheckDrawSpec(const SimObject& object, const DrawSpec& spec, const std::string& name);

}  // namespace gipsi
GIPSI_EXPORT_END
