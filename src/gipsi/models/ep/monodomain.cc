/// @file
/// P1 tetrahedral monodomain object.

#include "gipsi/models/ep/monodomain.h"

#include <fmt/format.h>

#include "gipsi/base/error.h"
#include "gipsi/geometry/boundary.h"
#include "gipsi/models/ep/ep_tissue_json.h"

namespace gipsi {

Monodomain::Monodomain(std::string name, std::shared_ptr<const Mesh> mesh, EpTissueParams params)
    : EpTissue(std::move(name), std::move(params)) {
  if (mesh->tets.cols() == 0)
    throw InputError("the Monodomain object needs a tetrahedral domain mesh (this one has none)");
  if (params_.anisotropic() && !params_.fibre && !params_.fibre_rule)
    throw InputError(
        "the conductivity is anisotropic (longitudinal != transverse), so the object needs a "
        "fibre direction: add \"fibres\": {\"direction\": [1, 0, 0]}");
  SetGeometry(mesh, MakeBoundary(*mesh));
  const Vec3 fibre = params_.fibre.value_or(Vec3::UnitX()).normalized();
  fibres_ = params_.fibre_rule ? MakeTransmuralFibres(*mesh, *params_.fibre_rule).fibre
                               : Points(fibre.replicate(1, mesh->tets.cols()));
  f_fibre_ = DeclareField({"fibre", FieldLocation::kElement, 3, "1", FieldAccess::kReadWrite,
                           "fibre direction per element (normalised when written)"});
  InitTissue();
  Assemble();
}

P1ScalarOperators AssembleMonodomainOperators(const Mesh& mesh, const Points& fibres,
                                              const EpTissueParams& params) {
  const double dl = params.diffusivity_longitudinal();
  const double dt = params.diffusivity_transverse();
  return AssembleP1Scalar(
      mesh.nodes, mesh.tets, 1e3,  // m → mm
      [&](Index e) -> Mat3 {
        const Vec3 f = fibres.col(e);
        return dt * Mat3::Identity() + (dl - dt) * f * f.transpose();
      },
      !params.lumped_mass);
}

void Monodomain::Assemble() {
  P1ScalarOperators ops = AssembleMonodomainOperators(domain(), fibres_, params_);
  SetDiffusionOperator(std::move(ops.stiffness), std::move(ops.lumped_mass),
                       std::move(ops.consistent_mass));
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
        CheckEpTissueKeys(ctx, {"parallel"});
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
