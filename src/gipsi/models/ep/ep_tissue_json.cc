/// @file
/// Reading the monodomain scene keys.

#include "gipsi/models/ep/ep_tissue_json.h"

#include <fmt/format.h>

#include <limits>

#include "gipsi/base/error.h"
#include "gipsi/base/units.h"
#include "gipsi/geometry/region_json.h"
#include "gipsi/models/ep/cell_models.h"

namespace gipsi {
namespace {

const std::vector<std::string> kTissueKeys = {
    "cell",        "conductivity", "fibres",    "surface_to_volume",
    "capacitance", "splitting",    "diffusion", "reaction",
    "stimuli",     "clamps",       "activation"};

// {"longitudinal": σ_l, "transverse": σ_t} [S/m]; σ_l > 0, σ_t ≥ 0.
std::pair<double, double> ReadPair(const JsonNode& node) {
  node.CheckKeys({"longitudinal", "transverse"});
  const double l = ReadPositiveQuantity(node.At("longitudinal"), "S/m");
  const double t = ReadPositiveQuantity(node.At("transverse"), "S/m", /*allow_zero=*/true);
  return {l, t};
}

void ReadConductivity(const JsonNode& node, EpTissueParams& params) {
  if (node.is_number() || node.is_string()) {
    params.sigma_longitudinal = params.sigma_transverse = ReadPositiveQuantity(node, "S/m");
    return;
  }
  if (!node.is_object())
    node.Expected(
        "a conductivity [S/m], {\"longitudinal\": ..., \"transverse\": ...}, or "
        "{\"intracellular\": {...}, \"extracellular\": {...}}");
  if (node.Has("intracellular") || node.Has("extracellular")) {
    node.CheckKeys({"intracellular", "extracellular"});
    const auto [il, it] = ReadPair(node.At("intracellular"));
    const auto [el, et] = ReadPair(node.At("extracellular"));
    // The monodomain conductivity is the harmonic mean σ_i σ_e / (σ_i + σ_e) per direction.
    params.sigma_longitudinal = il * el / (il + el);
    params.sigma_transverse = it + et > 0 ? it * et / (it + et) : 0.0;
    return;
  }
  std::tie(params.sigma_longitudinal, params.sigma_transverse) = ReadPair(node);
}

PulseTrain ReadPulses(const JsonNode& node) {
  PulseTrain p;
  if (auto start = node.Find("start")) p.start = 1e3 * ReadPositiveQuantity(*start, "s", true);
  p.duration = 1e3 * ReadPositiveQuantity(node.At("duration"), "s");
  if (auto period = node.Find("period")) {
    p.period = 1e3 * ReadPositiveQuantity(*period, "s");
    if (p.period < p.duration)
      period->Expected(fmt::format("a period no shorter than the duration ({} ms)", p.duration));
    p.count = std::numeric_limits<int>::max() / 2;
  }
  if (auto count = node.Find("count")) {
    const std::int64_t n = count->AsInt();
    if (n < 1 || n > 1000000) count->Expected("an integer in [1, 1000000]");
    if (!node.Has("period") && n > 1) count->Fail("several pulses need a \"period\"");
    p.count = static_cast<int>(n);
  }
  return p;
}

}  // namespace

void CheckEpTissueKeys(const ObjectBuildContext& ctx, const std::vector<std::string>& extra) {
  // The common key would be accepted and then ignored: an EP tissue steps no mechanics.
  if (auto bcs = ctx.params.Find("boundary_conditions"))
    bcs->Fail(
        "an EP tissue takes no boundary conditions (they fix, move or load a solid): its "
        "boundary is insulated (no current leaves it); excite it with \"stimuli\" or "
        "\"clamps\"");
  std::vector<std::string> keys = ObjectBuildContext::CommonKeys();
  keys.insert(keys.end(), kTissueKeys.begin(), kTissueKeys.end());
  keys.insert(keys.end(), extra.begin(), extra.end());
  ctx.params.CheckKeys(keys);
}

EpTissueParams ParseEpTissueParams(const ObjectBuildContext& ctx) {
  const JsonNode& p = ctx.params;
  EpTissueParams params;
  params.cell = CreateCellModel(ctx.registry, p.At("cell"));
  ReadConductivity(p.At("conductivity"), params);
  if (auto fibres = p.Find("fibres")) {
    if (fibres->Has("rule")) {
      params.fibre_rule = ParseTransmuralFibreRule(*fibres);
    } else {
      fibres->CheckKeys({"direction"});
      params.fibre = fibres->Vector3("direction");
      if (params.fibre->norm() == 0) fibres->At("direction").Expected("a non-zero vector");
    }
  } else if (params.anisotropic()) {
    p.At("conductivity")
        .Fail(
            "the conductivity is anisotropic (longitudinal != transverse), so the object needs a "
            "fibre direction: add \"fibres\": {\"direction\": [1, 0, 0]}");
  }
  if (auto chi = p.Find("surface_to_volume"))
    params.surface_to_volume = ReadPositiveQuantity(*chi, "1/m");
  if (auto cm = p.Find("capacitance")) params.capacitance = ReadPositiveQuantity(*cm, "F/m^2");
  if (auto splitting = p.Find("splitting"))
    params.splitting = splitting->AsChoice({"Godunov", "Strang"}) == "Strang"
                           ? SplittingScheme::kStrang
                           : SplittingScheme::kGodunov;
  if (auto diffusion = p.Find("diffusion")) {
    diffusion->CheckKeys({"scheme", "mass", "linear_solver"});
    if (auto scheme = diffusion->Find("scheme"))
      params.theta =
          scheme->AsChoice({"BackwardEuler", "CrankNicolson"}) == "CrankNicolson" ? 0.5 : 1.0;
    if (auto mass = diffusion->Find("mass"))
      params.lumped_mass = mass->AsChoice({"lumped", "consistent"}) == "lumped";
    if (auto solver = diffusion->Find("linear_solver")) {
      // Defaults for this object (CG + Jacobi, 1e-8) where the scene is silent.
      LinearSolverOptions parsed = ParseLinearSolverOptions(*solver);
      if (!solver->Has("preconditioner")) parsed.preconditioner = params.linear.preconditioner;
      if (!solver->Has("tolerance")) parsed.tolerance = params.linear.tolerance;
      params.linear = parsed;
    }
  }
  // "parallel": {"linear_solver": {...}}: the diffusion solver when the object is split over
  // MPI ranks (PETSc's: "hypre" is BoomerAMG, "cholmod" and "ldlt" MUMPS's Cholesky); keys it
  // leaves out keep the diffusion's. Checked in every run, used only in distributed ones.
  if (auto parallel = p.Find("parallel")) {
    parallel->CheckKeys({"linear_solver"});
    const JsonNode solver = parallel->At("linear_solver");
    solver.CheckKeys({"type", "preconditioner", "tolerance", "max_iterations"});
    LinearSolverOptions distributed = params.linear;
    if (auto type = solver.Find("type"))
      distributed.type = type->AsChoice({"cg", "cholmod", "ldlt"});
    if (auto preconditioner = solver.Find("preconditioner"))
      distributed.preconditioner = preconditioner->AsChoice({"none", "jacobi", "amg", "hypre"});
    distributed.tolerance = solver.Positive("tolerance", distributed.tolerance);
    if (auto max_iterations = solver.Find("max_iterations")) {
      const std::int64_t n = max_iterations->AsInt();
      if (n < 1 || n > 1000000) max_iterations->Expected("a number of iterations in [1, 1000000]");
      distributed.max_iterations = static_cast<int>(n);
    }
    params.distributed_linear = distributed;
  }
  if (auto reaction = p.Find("reaction")) {
    reaction->CheckKeys({"dt"});
    params.reaction_dt = ReadPositiveQuantity(reaction->At("dt"), "s");
  }
  if (auto stimuli = p.Find("stimuli")) {
    if (!stimuli->is_object()) stimuli->Expected("an object of named stimuli");
    for (const auto& [name, s] : stimuli->Members()) {
      s.CheckKeys({"region", "current", "amplitude", "start", "duration", "period", "count"});
      StimulusSpec spec;
      spec.name = name;
      spec.region = ParseRegion(s.At("region"));
      if (s.Has("current") == s.Has("amplitude"))
        s.Fail(
            "give exactly one of \"current\" (per tissue volume, A/m^3, e.g. \"50000 "
            "uA/cm^3\") or \"amplitude\" (per membrane capacitance, A/F, e.g. \"35.7 uA/uF\")");
      // A/F = V/s, numerically mV/ms: the cell models' unit.
      if (auto current = s.Find("current"))
        spec.amplitude =
            ReadQuantity(*current, "A/m^3") / (params.surface_to_volume * params.capacitance);
      else
        spec.amplitude = ReadQuantity(s.At("amplitude"), "A/F");
      spec.pulses = ReadPulses(s);
      params.stimuli.push_back(std::move(spec));
    }
  }
  if (auto clamps = p.Find("clamps")) {
    if (!clamps->is_object()) clamps->Expected("an object of named clamps");
    for (const auto& [name, c] : clamps->Members()) {
      c.CheckKeys({"region", "voltage", "start", "duration", "period", "count"});
      ClampSpec spec;
      spec.name = name;
      spec.region = ParseRegion(c.At("region"));
      spec.voltage = 1e3 * ReadQuantity(c.At("voltage"), "V");
      spec.pulses = ReadPulses(c);
      params.clamps.push_back(std::move(spec));
    }
  }
  if (auto activation = p.Find("activation")) {
    activation->CheckKeys({"threshold", "apd_repolarisation"});
    if (auto threshold = activation->Find("threshold"))
      params.activation_threshold = 1e3 * ReadQuantity(*threshold, "V");
    if (auto fraction = activation->Find("apd_repolarisation")) {
      params.apd_repolarisation = fraction->AsNumber();
      if (!(params.apd_repolarisation > 0 && params.apd_repolarisation < 1))
        fraction->Expected("a fraction in (0, 1), e.g. 0.9 for APD90");
    }
  }
  return params;
}

}  // namespace gipsi
