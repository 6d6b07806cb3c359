// MassSpring's muscle terms: the per-spring weights that turn a nodal active tension [Pa] into
// spring forces [N] equivalent to the stress T f ⊗ f, and the tets' volume term (the
// derivations are in mass_spring.h).

#include <cmath>
#include <limits>
#include <map>
#include <utility>

#include "gipsi/base/error.h"
#include "gipsi/geometry/quality.h"
#include "gipsi/models/mass_spring/mass_spring.h"

namespace gipsi {

void MassSpring::UpdateActiveWeights() {
  weights_stamp_ = state_.fibres.stamp();
  active_weight_ = VecX::Zero(num_springs());
  const Mesh& mesh = domain();
  if (mesh.num_tets() == 0 || state_.fibres.get().cols() != mesh.num_tets()) return;
  std::map<std::pair<int, int>, Index> spring_of;
  for (Index s = 0; s < num_springs(); ++s)
    spring_of.emplace(std::minmax(springs_(0, s), springs_(1, s)), s);
  for (Index e = 0; e < mesh.num_tets(); ++e) {
    const Vec3 f = state_.fibres.get().col(e);
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

void MassSpring::AddVolumeForces(Eigen::Ref<const VecX> q, Eigen::Ref<VecX> f) const {
  if (params_.volume_stiffness == 0) return;
  const Tets& tets = domain().tets;
  for (Index e = 0; e < tets.cols(); ++e) {
    const Vec3 x0 = q.segment<3>(3 * tets(0, e)), x1 = q.segment<3>(3 * tets(1, e)),
               x2 = q.segment<3>(3 * tets(2, e)), x3 = q.segment<3>(3 * tets(3, e));
    const Vec3 a = x1 - x0, b = x2 - x0, c = x3 - x0;
    const double volume = a.dot(b.cross(c)) / 6.0;
    // −∂/∂x of (K/2) V0 (ln J)², J = V/V0: −K (ln J / J) ∂V/∂x, with 6 ∂V/∂x1 = b × c, etc.
    // An inverted tet (J ≤ 0) gets no force here; CheckState reports it.
    const double j = volume / tet_rest_volume_[e];
    if (!(j > 0)) continue;
    const double s =
        -std::copysign(params_.volume_stiffness, tet_rest_volume_[e]) * std::log(j) / j / 6.0;
    const Vec3 g1 = s * b.cross(c), g2 = s * c.cross(a), g3 = s * a.cross(b);
    f.segment<3>(3 * tets(1, e)) += g1;
    f.segment<3>(3 * tets(2, e)) += g2;
    f.segment<3>(3 * tets(3, e)) += g3;
    f.segment<3>(3 * tets(0, e)) -= g1 + g2 + g3;
  }
}

Index MassSpring::FirstInvertedTet() const {
  if (params_.volume_stiffness == 0) return -1;
  const Tets& tets = domain().tets;
  for (Index e = 0; e < tets.cols(); ++e) {
    const double volume =
        TetSignedVolume(state_.x.segment<3>(3 * tets(0, e)), state_.x.segment<3>(3 * tets(1, e)),
                        state_.x.segment<3>(3 * tets(2, e)), state_.x.segment<3>(3 * tets(3, e)));
    if (!(volume / tet_rest_volume_[e] > 0)) return e;
  }
  return -1;
}

double MassSpring::VolumeEnergy() const {
  if (params_.volume_stiffness == 0) return 0;
  const Tets& tets = domain().tets;
  double energy = 0;
  for (Index e = 0; e < tets.cols(); ++e) {
    const double volume =
        TetSignedVolume(state_.x.segment<3>(3 * tets(0, e)), state_.x.segment<3>(3 * tets(1, e)),
                        state_.x.segment<3>(3 * tets(2, e)), state_.x.segment<3>(3 * tets(3, e)));
    const double j = volume / tet_rest_volume_[e];
    const double log_j = j > 0 ? std::log(j) : std::numeric_limits<double>::infinity();
    energy += 0.5 * params_.volume_stiffness * std::abs(tet_rest_volume_[e]) * log_j * log_j;
  }
  return energy;
}

}  // namespace gipsi
