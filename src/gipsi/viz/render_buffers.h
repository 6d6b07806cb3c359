#pragma once
/// @file
/// The standard format the visualization tool draws: per object, vertex positions, normals,
/// colours and the indices of triangles, line segments or points (GiPSi's display-manager
/// output). Plain data, filled by display
/// managers on the simulation thread and published to renderers through a `LatestValue`
/// (base/latest_value.h).

#include <cstdint>
#include <string>
#include <vector>

#include "gipsi/base/export.h"
#include "gipsi/io/display_spec.h"  // Primitive

GIPSI_EXPORT_BEGIN
namespace gipsi::viz {

/// One object's display geometry (a surface, a line set or a point set). Vectors are flat,
/// vertex-major (x0 y0 z0 x1 ...), ready for OpenGL vertex buffers. Copyable and movable; refilling
/// keeps the capacity.
struct SurfaceBuffers {
  std::string object;            ///< leaf object name
  std::vector<float> positions;  ///< 3V, scene units
  /// 3V, unit (zero at vertices of degenerate triangles, and for lines and points, which are
  /// drawn unshaded)
  std::vector<float> normals;
  std::vector<float> colors;  ///< 3V, sRGB in [0, 1]
  std::vector<float> values;  ///< V field values behind the colours (empty if solid)
  /// Triangles: 3T, counter-clockwise seen from outside; lines: 2 per segment; points: 1 each.
  std::vector<std::uint32_t> indices;
  Primitive primitive = Primitive::kTriangles;
  bool wireframe = false;  ///< triangles: also draw their edges (the object's own choice)
  float size = 1;          ///< lines: width, points: diameter, in pixels of the final image
  /// Colour field label, e.g. "|displacement|", "position x"; "" for a solid colour.
  std::string field;
  std::string units;                  ///< its units
  std::string color_map;              ///< colour map name ("" if solid)
  double range_lo = 0, range_hi = 0;  ///< the value range the colours span
  /// Vertices whose field holds its no-data marker (FieldInfo::no_data, e.g. -1 for "not
  /// activated yet"): drawn in kNoDataColor, left out of the range; the values hold NaN there.
  std::size_t num_no_data = 0;

  [[nodiscard]] std::size_t num_vertices() const { return positions.size() / 3; }
  /// Number of triangles (0 for lines and points).
  [[nodiscard]] std::size_t num_triangles() const {
    return primitive == Primitive::kTriangles ? indices.size() / 3 : 0;
  }
};

/// The colour of vertices without data (a light grey).
inline constexpr float kNoDataColor[3] = {0.75f, 0.75f, 0.75f};

/// Recent samples of one probe, for live plots. Copyable and movable.
struct ProbeTrace {
  std::string name;                  ///< probe name
  std::vector<std::string> columns;  ///< CSV columns after time
  /// Per column: readable label, display unit ("" for none), the factor from the column's SI
  /// values to that unit, and its no-data marker (NaN: none) in SI.
  std::vector<std::string> labels, units;
  std::vector<double> scales, no_data;
  std::vector<float> time;                 ///< sample times [s], oldest first
  std::vector<std::vector<float>> values;  ///< values[c][k]: column c at time[k]
};

/// Everything drawn in one frame. Copyable and movable.
struct FrameBuffers {
  double time = 0;          ///< simulated time [s]
  std::int64_t frame = -1;  ///< publication counter (-1: nothing published yet)
  std::vector<SurfaceBuffers> surfaces;
  std::vector<ProbeTrace> traces;  ///< filled by viewers that plot probes live
};

}  // namespace gipsi::viz
GIPSI_EXPORT_END
