/// @file
/// P1 tetrahedral monodomain object.

#include "gipsi/models/ep/monodomain.h"

#include <fmt/format.h>

#include <Eigen/Dense>

#include "gipsi/base/error.h"
#include "gipsi/geometry/boundary.h"
#include "gipsi/models/ep/ep_tissue_json.h"

namespace gipsi {

Monodomain::Monodomain(std::string name, std::shared_ptr<const Mesh> mesh, EpTissueParams params)
    : EpTissue(std::move(name), std::move(params)) {
  if (mesh->tets.cols() == 0)
    throw InputError("the Monodomain object needs a tetrahedral domain mesh (this one has none)");
  if (params_.anisotropic() && !params_.fibre)
    throw InputError(
        "the conductivity is anisotropic (longitudinal != transverse), so the object needs a "
        "fibre direction: add \"fibres\": {\"direction\": [1, 0, 0]}");
  SetGeometry(mesh, MakeBoundary(*mesh));
  const Vec3 fibre = params_.fibre.value_or(Vec3::UnitX()).normalized();
  fibres_ = fibre.replicate(1, mesh->tets.cols());
  f_fibre_ = DeclareField({"fibre", FieldLocation::kElement, 3, "1", FieldAccess::kReadWrite,
                           "fibre direction per element (normalised when written)"});
  InitTissue();
  Assemble();
}

void Monodomain::Assemble() {
  const Mesh& mesh = domain();
  const Index num_tets = mesh.tets.cols();
  const double dl = params_.diffusivity_longitudinal();
  const double dt = params_.diffusivity_transverse();
  std::vector<Eigen::Triplet<double, int>> k_entries, m_entries;
  k_entries.reserve(static_cast<std::size_t>(16 * num_tets));
  if (!params_.lumped_mass) m_entries.reserve(static_cast<std::size_t>(16 * num_tets));
  VecX lumped = VecX::Zero(mesh.num_nodes());
  for (Index e = 0; e < num_tets; ++e) {
    Mat3 edges;
    const Vec3 x0 = 1e3 * mesh.nodes.col(mesh.tets(0, e));  // mm
    for (int a = 0; a < 3; ++a) edges.col(a) = 1e3 * mesh.nodes.col(mesh.tets(a + 1, e)) - x0;
    const double volume = edges.determinant() / 6.0;
    if (!(std::abs(volume) > 1e-300))
      throw InputError(fmt::format("tet {} of the domain mesh is degenerate (zero volume)", e));
    // Gradients of the barycentric functions: rows of edges⁻¹ for nodes 1..3; node 0 their
    // negative sum.
    const Mat3 inv = edges.inverse();
    Eigen::Matrix<double, 4, 3> grad;
    grad.bottomRows<3>() = inv;
    grad.row(0) = -inv.colwise().sum();
    const Vec3 f = fibres_.col(e);
    const Mat3 diffusivity = dt * Mat3::Identity() + (dl - dt) * f * f.transpose();
    const Eigen::Matrix4d ke = std::abs(volume) * grad * diffusivity * grad.transpose();
    for (int a = 0; a < 4; ++a) {
      const int ia = mesh.tets(a, e);
      lumped[ia] += std::abs(volume) / 4;
      for (int b = 0; b < 4; ++b) {
        const int ib = mesh.tets(b, e);
        k_entries.emplace_back(ia, ib, ke(a, b));
        if (!params_.lumped_mass)
          m_entries.emplace_back(ia, ib, std::abs(volume) * (a == b ? 2.0 : 1.0) / 20.0);
      }
    }
  }
  const auto n = static_cast<int>(mesh.num_nodes());
  SparseMatrix stiffness(n, n);
  stiffness.setFromTriplets(k_entries.begin(), k_entries.end());
  SparseMatrix mass;
  if (!params_.lumped_mass) {
    mass.resize(n, n);
    mass.setFromTriplets(m_entries.begin(), m_entries.end());
  }
  SetDiffusionOperator(std::move(stiffness), std::move(lumped), std::move(mass));
}

void Monodomain::DoReadField(FieldId id, Eigen::Ref<Eigen::MatrixXd> out) const {
  if (id == f_fibre_) {
    out = fibres_;
    return;
  }
  EpTissue::DoReadField(id, out);
}

void Monodomain::DoWriteField(FieldId id, const Eigen::Ref<const Eigen::MatrixXd>& in) {
  if (id != f_fibre_) {
    EpTissue::DoWriteField(id, in);
    return;
  }
  for (Index e = 0; e < in.cols(); ++e) {
    const Vec3 f = in.col(e);
    const double norm = f.norm();
    // A zero or non-finite direction keeps the element's previous fibre.
    if (norm > 0 && std::isfinite(norm)) fibres_.col(e) = f / norm;
  }
  Assemble();
}

void RegisterMonodomain(TypeRegistry& registry) {
  registry.objects.Register(
      "Monodomain",
      [](const ObjectBuildContext& ctx) -> std::unique_ptr<SimObject> {
        CheckEpTissueKeys(ctx);
        EpTissueParams params = ParseEpTissueParams(ctx);
        try {
          return std::make_unique<Monodomain>(ctx.name, ctx.DomainMesh(), std::move(params));
        } catch (const InputError& e) {
          ctx.params.Fail(e.what());
        }
      },
      "cardiac monodomain reaction-diffusion on P1 tetrahedra (operator splitting)");
}

}  // namespace gipsi
