#pragma once
/// @file
/// Display managers: convert a simulation object's display geometry into the standard render
/// buffers (positions, normals, colours, indices), colouring by a named field through a colour
/// map. Models never draw; renderers only see `SurfaceBuffers`. What to draw comes as the plain
/// specifications of io/display_spec.h (a scene's "display" keys, the command line's colours).

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "gipsi/base/export.h"
#include "gipsi/core/kernel.h"
#include "gipsi/core/sim_object.h"
#include "gipsi/io/display_spec.h"
#include "gipsi/viz/color_map.h"
#include "gipsi/viz/render_buffers.h"

GIPSI_EXPORT_BEGIN
namespace gipsi::viz {

/// Fills one object's `SurfaceBuffers` from its display geometry: its display surface
/// (triangles), its springs or mesh edges (lines) or its nodes (points). Built once (it
/// resolves the field and precomputes the mapping to display vertices); `Fill` allocates
/// nothing after the first call on the same buffers. Not copyable (holds a reference); movable.
class DisplayManager {
 public:
  /// Throws InputError (naming the object) for a spec that CheckDrawSpec refuses: an unknown or
  /// unreadable field, a component out of range, an unsupported field location, an unknown
  /// colour map, an empty range, or a geometry the object does not have.
  /// `name` is the object's full dotted name (Kernel::ObjectPath), used in the buffers and in
  /// messages; empty: the object's own name.
  DisplayManager(const SimObject& object, DrawSpec spec, std::string name = {});
  /// The object drawn in its default way, coloured by `spec`.
  DisplayManager(const SimObject& object, ColorSpec spec);

  /// Draws the object on the current geometry of `other`, an object on the very same domain
  /// mesh (e.g. a heart's bioelectricity on its moving muscle: the same tissue), instead of on
  /// its own (rest) node positions. Precondition (checked): the same domain mesh.
  void DrawOn(const SimObject& other);
  /// The object whose geometry it is drawn on: `other` of DrawOn, else the object itself.
  [[nodiscard]] const SimObject& geometry_object() const { return *geometry_; }

  /// Whether the object has something to draw by default (see DrawSpec::as).
  static bool HasDefaultGeometry(const SimObject& object);

  [[nodiscard]] const SimObject& object() const { return *object_; }
  /// The object's full dotted name (SurfaceBuffers::object).
  [[nodiscard]] const std::string& name() const { return name_; }
  [[nodiscard]] const ColorSpec& spec() const { return draw_.color; }
  [[nodiscard]] const DrawSpec& draw() const { return draw_; }
  [[nodiscard]] Primitive primitive() const { return primitive_; }
  /// Recomputes the display positions from the object's state and writes all buffers. Call on
  /// the thread that steps the object (between steps).
  void Fill(SurfaceBuffers& out);

 private:
  void ComputeValues();  // values_ at display vertices

  const SimObject* object_;
  const SimObject* geometry_;  // whose node positions it is drawn on
  DrawSpec draw_;
  std::string name_;
  Primitive primitive_ = Primitive::kTriangles;
  std::vector<std::uint32_t> segments_;  // lines: node pairs
  ColorMap map_;
  std::optional<FieldId> field_;
  std::string label_;  // e.g. "|displacement|"
  FieldLocation location_ = FieldLocation::kNode;
  // Element -> node averaging (CSR over nodes), when the field lives on elements.
  std::vector<int> node_elem_start_, node_elems_;
  Eigen::MatrixXd raw_;      // components by items
  Eigen::RowVectorXd item_;  // scalar per item
  Eigen::RowVectorXd node_;  // scalar per node (element fields)
  Eigen::RowVectorXd values_;
  Points normals_ = Points(3, 0);
  Points positions_ = Points(3, 0);  // display positions on another object's geometry
};

/// Display managers for every leaf object of a kernel that has something to draw (see
/// DrawSpec::as) or that the scene asks to draw, and `Fill` for all of them into one frame.
/// An object without mechanics (no "position" field) on the same domain mesh as one with
/// mechanics is drawn on that one's moving geometry (DisplayManager::DrawOn: a heart's
/// bioelectricity on its muscle), and the mechanical one starts hidden unless the scene draws
/// it or the command line colours it (both on one surface would fight for its pixels).
/// Each is drawn as the scene's spec says (`scene_specs`, from the objects' "display" keys),
/// with its colour replaced by `colors[name]` when given (the command line's choice); objects
/// without a colour get solid colours from a fixed palette. Not copyable; movable.
class SceneDisplay {
 public:
  /// Throws InputError for a colour naming no such object or an invalid spec.
  SceneDisplay(const Kernel& kernel, const std::vector<std::pair<std::string, ColorSpec>>& colors);
  SceneDisplay(const Kernel& kernel,
               const std::vector<std::pair<const SimObject*, DrawSpec>>& scene_specs,
               const std::vector<std::pair<std::string, ColorSpec>>& colors);
  /// Each manager's full object name and colour, e.g. to draw a reloaded scene (the viewer's
  /// reset) as this one is drawn.
  [[nodiscard]] std::vector<std::pair<std::string, ColorSpec>> Colors() const;
  /// Hidden flags for RenderOptions::hidden: !visible of each manager's spec.
  [[nodiscard]] std::vector<bool> Hidden() const;
  [[nodiscard]] std::size_t size() const { return managers_.size(); }
  [[nodiscard]] DisplayManager& manager(std::size_t i) { return managers_[i]; }
  /// Fills `out` (one surface per manager) at simulated time `t`.
  void Fill(double t, FrameBuffers& out);

 private:
  std::vector<DisplayManager> managers_;
  std::int64_t frames_ = 0;
};

/// Whether the viewer offers field `id` of `object` to colour by: a readable node or element
/// field, or a boundary-vertex field of an object drawn with its own boundary; a writable one
/// (an input such as a MassSpring's `fibre` or `nodal_active_tension`, or `external_force`) only
/// if its items hold more than one value, so inputs that nothing in the scene drives are not
/// offered; the mechanical state (`position`, `velocity`) always. Reads the field (allocates).
bool OffersField(const SimObject& object, FieldId id);

/// The viewer's component box for a field with `components` values per item, in
/// ColorSpec::component order from -1: "magnitude", then one name per component ("x", "y", "z"
/// for a vector, "[k]" otherwise, as the colour bar labels them). Empty for a scalar, which is
/// drawn as its value with its sign: the viewer shows no component box for it.
std::vector<std::string> ComponentChoices(int components);

/// The default colour of an object the scene and command line leave uncoloured: an
/// electrophysiology object (a readable node field "V", the transmembrane potential) is coloured
/// by V through the cool-warm map; std::nullopt for others (solid colours).
std::optional<ColorSpec> DefaultColor(const SimObject& object);

/// Applies the command line's `--as OBJECT:surface|lines|points` choices (`options`) to a
/// scene's draw specs (adding one for an object that has none). Throws InputError naming
/// `option` for bad syntax or an unknown object.
void ApplyGeometryOptions(const Kernel& kernel, const std::vector<std::string>& options,
                          std::string_view option,
                          std::vector<std::pair<const SimObject*, DrawSpec>>& specs);

/// Applies the command line's `--show` and `--hide` (object names, resolved by
/// Kernel::FindObject: full dotted names, or a part's own name when unambiguous) to `hidden`
/// (one flag per drawn object, whose full names are `names`). Throws InputError naming the
/// option for an unknown name or an object that is not drawn.
void ApplyVisibility(const Kernel& kernel, const std::vector<std::string>& names,
                     const std::vector<std::string>& show, const std::vector<std::string>& hide,
                     std::vector<bool>& hidden);

}  // namespace gipsi::viz
GIPSI_EXPORT_END
