#pragma once
/// @file
/// Display managers: convert a simulation object's display geometry into the standard render
/// buffers (positions, normals, colours, indices), colouring by a named field through a colour
/// map. Models never draw; renderers only see `SurfaceBuffers`.

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "gipsi/base/json_node.h"
#include "gipsi/core/kernel.h"
#include "gipsi/core/sim_object.h"
#include "gipsi/viz/color_map.h"
#include "gipsi/viz/render_buffers.h"

namespace gipsi::viz {

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

/// Parses {"field": "displacement", "component": "magnitude"|0|1|2|"x"|"y"|"z",
/// "map": "viridis", "range": [lo, hi], "color": [r, g, b]}; throws InputError naming the path.
ColorSpec ParseColorSpec(const JsonNode& node);

/// Parses a command-line colour choice "OBJECT:FIELD" where FIELD may end in ".x", ".y", ".z"
/// (or ".0" ... ".8") for one component (else the magnitude), with colour map `map` and
/// optional fixed `range`. Throws InputError naming `option` (e.g. "--color").
std::pair<std::string, ColorSpec> ParseColorOption(std::string_view text, std::string_view map,
                                                   std::optional<std::pair<double, double>> range,
                                                   std::string_view option);

/// Fills one object's `SurfaceBuffers` from its display geometry. Built once (it resolves the
/// field and precomputes the mapping to display vertices); `Fill` allocates nothing after the
/// first call on the same buffers. Not copyable (holds a reference); movable.
class DisplayManager {
 public:
  /// Throws InputError (naming the object) for an unknown or unreadable field, a component out
  /// of range, an unsupported field location, an unknown colour map or an empty range.
  DisplayManager(const SimObject& object, ColorSpec spec);

  [[nodiscard]] const SimObject& object() const { return *object_; }
  [[nodiscard]] const ColorSpec& spec() const { return spec_; }
  /// Recomputes the display positions from the object's state and writes all buffers. Call on
  /// the thread that steps the object (between steps).
  void Fill(SurfaceBuffers& out);

 private:
  void ComputeValues();  // values_ at display vertices

  const SimObject* object_;
  ColorSpec spec_;
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
};

/// Display managers for every leaf object of a kernel that has a display surface, coloured by
/// `specs[name]` when given (else solid colours from a fixed palette), and `Fill` for all of
/// them into one frame. Not copyable; movable.
class SceneDisplay {
 public:
  /// Throws InputError for a spec naming no such object or an invalid spec.
  SceneDisplay(const Kernel& kernel, const std::vector<std::pair<std::string, ColorSpec>>& specs);
  [[nodiscard]] std::size_t size() const { return managers_.size(); }
  [[nodiscard]] DisplayManager& manager(std::size_t i) { return managers_[i]; }
  /// Fills `out` (one surface per manager) at simulated time `t`.
  void Fill(double t, FrameBuffers& out);

 private:
  std::vector<DisplayManager> managers_;
  std::int64_t frames_ = 0;
};

}  // namespace gipsi::viz
