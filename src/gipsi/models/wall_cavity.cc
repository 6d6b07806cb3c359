/// @file
/// Cavities of a wall, shared by FemSolid and MassSpring (wall_cavity.h).

#include "gipsi/models/wall_cavity.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "gipsi/base/error.h"
#include "gipsi/geometry/region_json.h"

namespace gipsi {

std::vector<CavitySpec> ParseCavitySpecs(const JsonNode& node) {
  std::vector<CavitySpec> specs;
  for (const auto& [name, region] : node.Members())
    specs.push_back(CavitySpec{name, ParseRegion(region)});
  return specs;
}

double WallCavity::Volume(const Points& x, bool gradient) const {
  for (std::size_t k = 0; k < nodes.size(); ++k)
    positions.col(static_cast<Index>(k)) = x.col(nodes[k]);
  return volume.Compute(positions, gradient ? &local_gradient : nullptr);
}

std::vector<WallCavity> MakeWallCavities(std::string_view object, std::span<const CavitySpec> specs,
                                         const Mesh& mesh, const BoundarySurface& boundary,
                                         const std::function<FieldId(FieldInfo)>& declare,
                                         std::string_view pressure_description) {
  std::vector<WallCavity> cavities;
  for (const CavitySpec& spec : specs)
    cavities.push_back(MakeWallCavity(object, spec, boundary,
                                      SelectBoundaryFaces(spec.region, mesh, boundary), declare,
                                      pressure_description));
  return cavities;
}

WallCavity MakeWallCavity(std::string_view object, const CavitySpec& spec,
                          const BoundarySurface& boundary, std::vector<int> faces,
                          const std::function<FieldId(FieldInfo)>& declare,
                          std::string_view pressure_description) {
  if (faces.empty())
    throw InputError(
        fmt::format("object '{}': cavity '{}' selects no boundary face", object, spec.name));
  CavitySurface surface = MakeCavitySurface(boundary, faces);
  const auto nc = static_cast<Index>(surface.nodes.size());
  EnclosedVolume volume = [&] {
    try {
      return EnclosedVolume(surface.triangles, nc);
    } catch (const InputError& e) {
      throw InputError(fmt::format("object '{}': cavity '{}': {}", object, spec.name, e.what()));
    }
  }();
  const FieldId f_volume =
      declare({spec.name + "_volume", FieldLocation::kGlobal, 1, "m^3", FieldAccess::kRead,
               "volume enclosed by the cavity's faces (rim capped)"});
  const FieldId f_pressure = declare({spec.name + "_pressure", FieldLocation::kGlobal, 1, "Pa",
                                      FieldAccess::kReadWrite, std::string(pressure_description)});
  return WallCavity{.faces = std::move(faces),
                    .nodes = std::move(surface.nodes),
                    .volume = std::move(volume),
                    .positions = Points::Zero(3, nc),
                    .local_gradient = Points::Zero(3, nc),
                    .f_volume = f_volume,
                    .f_pressure = f_pressure};
}

double CavityLawStiffness(CavityLaw& law, double t, double dt, double p, double vb) {
  const double dp = std::max(1e-3, 1e-6 * std::abs(p));
  double v1 = 0;
  if (law.EndVolume(t, dt, p + dp, v1) && std::isfinite(v1) && vb > v1) return dp / (vb - v1);
  return 0;
}

std::vector<std::string> CavityNames(std::span<const CavitySpec> specs) {
  std::vector<std::string> names;
  for (const CavitySpec& spec : specs) names.push_back(spec.name);
  return names;
}

std::size_t FindCavity(std::string_view object, std::string_view type,
                       std::span<const CavitySpec> specs, std::string_view cavity) {
  for (std::size_t i = 0; i < specs.size(); ++i)
    if (specs[i].name == cavity) return i;
  const std::vector<std::string> names = CavityNames(specs);
  throw InputError(
      fmt::format("object '{}' ({}) has no cavity '{}'; its cavities: {}", object, type, cavity,
                  names.empty() ? std::string("none") : fmt::format("{}", fmt::join(names, ", "))));
}

void ThrowCavityAlreadyCoupled(std::string_view object, std::string_view cavity) {
  throw InputError(
      fmt::format("object '{}': cavity '{}' is already coupled to blood", object, cavity));
}

}  // namespace gipsi
