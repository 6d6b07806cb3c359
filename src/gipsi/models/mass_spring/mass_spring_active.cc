// MassSpring's active tension: the per-spring weights that turn a nodal tension [Pa] into
// spring forces [N] equivalent to the stress T f ⊗ f (the derivation is in mass_spring.h).

#include <cmath>
#include <map>
#include <utility>

#include "gipsi/base/error.h"
#include "gipsi/geometry/quality.h"
#include "gipsi/models/mass_spring/mass_spring.h"

namespace gipsi {

void MassSpring::UpdateActiveWeights() {
  active_weight_ = VecX::Zero(num_springs());
  const Mesh& mesh = domain();
  if (mesh.num_tets() == 0 || fibres_.cols() != mesh.num_tets()) return;
  std::map<std::pair<int, int>, Index> spring_of;
  for (Index s = 0; s < num_springs(); ++s)
    spring_of.emplace(std::minmax(springs_(0, s), springs_(1, s)), s);
  for (Index e = 0; e < mesh.num_tets(); ++e) {
    const Vec3 f = fibres_.col(e);
    const double volume =
        std::abs(TetSignedVolume(mesh.nodes.col(mesh.tets(0, e)), mesh.nodes.col(mesh.tets(1, e)),
                                 mesh.nodes.col(mesh.tets(2, e)), mesh.nodes.col(mesh.tets(3, e))));
    Index edge[6];
    double cos2[6];
    double sum4 = 0;
    int k = 0;
    for (int i = 0; i < 4; ++i)
      for (int j = i + 1; j < 4; ++j, ++k) {
        const int a = mesh.tets(i, e), b = mesh.tets(j, e);
        edge[k] = spring_of.at(std::minmax(a, b));
        const Vec3 d = (mesh.nodes.col(b) - mesh.nodes.col(a)).normalized();
        cos2[k] = d.dot(f) * d.dot(f);
        sum4 += cos2[k] * cos2[k];
      }
    // A non-degenerate tet's edges span space, so some d̂·f ≠ 0 and sum4 > 0.
    GIPSI_CHECK(sum4 > 0);
    const double c = 6.0 / sum4;
    for (k = 0; k < 6; ++k)
      active_weight_[edge[k]] += c * (volume / 6.0) * cos2[k] / rest_length_[edge[k]];
  }
}

}  // namespace gipsi
