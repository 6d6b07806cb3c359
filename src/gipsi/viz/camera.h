#pragma once
/// @file
/// `Camera`: an orbit camera (target, distance, azimuth, elevation; z up) and its view and
/// projection matrices, shared by the off-screen snapshot and the interactive viewer.

#include <string_view>

#include "gipsi/base/math.h"

#include "gipsi/base/export.h"
#include "gipsi/viz/render_buffers.h"

GIPSI_EXPORT_BEGIN
namespace gipsi::viz {

/// Orbit camera looking at `target` from `distance`; the eye direction is given by `azimuth`
/// (degrees about +z; 0 puts the eye on the -y side, 90 on the +x side) and `elevation`
/// (degrees above the xy plane). Plain struct.
struct Camera {
  Eigen::Vector3d target = Eigen::Vector3d::Zero();
  double distance = 1;          ///< scene units, > 0
  double azimuth = -60;         ///< degrees; 0: the eye is on the -y side of the target
  double elevation = 25;        ///< degrees in (-90, 90)
  double fov_y = 30;            ///< vertical field of view, degrees
  bool distance_given = false;  ///< true if the user fixed the distance (FitTo keeps it)

  /// Eye position in scene coordinates.
  [[nodiscard]] Eigen::Vector3d Eye() const;
  /// World-to-camera matrix (OpenGL convention: the camera looks along -z).
  [[nodiscard]] Eigen::Matrix4f View() const;
  /// Perspective projection for a width/height `aspect`; near and far planes at 0.01 and 10
  /// times the distance.
  [[nodiscard]] Eigen::Matrix4f Projection(double aspect) const;
  /// Aims at the centre of the bounding box of every surface in `frame` and (unless
  /// distance_given) backs off until the whole box is in view, with a 10 % margin.
  void FitTo(const FrameBuffers& frame, double aspect);
  /// The ray (origin on the near plane, unit direction) through the point (ndc_x, ndc_y) of
  /// normalised device coordinates (-1 to 1, y up) of a view with width/height `aspect`.
  [[nodiscard]] std::pair<Eigen::Vector3d, Eigen::Vector3d> Ray(double ndc_x, double ndc_y,
                                                                double aspect) const;
  /// Orbit by mouse-like deltas (degrees); elevation is clamped to ±89°.
  void Orbit(double d_azimuth, double d_elevation);
};

/// Parses "AZIMUTH,ELEVATION[,DISTANCE]" (degrees, degrees, scene units) into `camera`; throws
/// InputError naming `where` and saying what was expected.
void ParseCamera(std::string_view text, std::string_view where, Camera& camera);

}  // namespace gipsi::viz
GIPSI_EXPORT_END
