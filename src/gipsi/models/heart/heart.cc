#include "gipsi/models/heart/heart.h"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "gipsi/base/error.h"
#include "gipsi/base/log.h"
#include "gipsi/base/units.h"

namespace gipsi {
namespace {

/// The default heart: a left ventricle on the scene's mesh "lv" (an "ellipsoid_shell" with
/// groups endo, epi and base), Mitchell–Schaeffer cells stimulated at the apex every 0.8 s,
/// Guccione myocardium with rule-based fibres (+60° endocardium to −60° epicardium) and its base
/// held, and the closed-loop circulation with the LV as the 3-D cavity. docs/heart.md lists the
/// parameters and why they are what they are.
constexpr const char* kHeartDefaults = R"({
  "dt": "5 ms",
  "parts": {
    "bioelectricity": {
      "type": "Monodomain", "domain": "lv", "dt": "0.1 ms",
      "cell": {"model": "MitchellSchaeffer"},
      "conductivity": {"longitudinal": "3 S/m", "transverse": "0.75 S/m"},
      "fibres": {"rule": "transmural", "endo": {"group": "endo"}, "epi": {"group": "epi"},
                 "axis": [0, 0, 1], "endo_angle": 60, "epi_angle": -60},
      "stimuli": {"apex": {"region": {"sphere": {"center": [0, 0, -0.05], "radius": 0.01}},
                           "amplitude": "50 uA/uF", "duration": "2 ms", "period": "0.8 s"}},
      "activation": {"threshold": "-40 mV"}
    },
    "muscle": {
      "type": "FemSolid", "domain": "lv", "dt": "5 ms",
      "material": {"law": "Guccione", "C": 1000, "bf": 8, "bt": 2, "bfs": 4,
                   "bulk_modulus": 50000},
      "fibres": {"rule": "transmural", "endo": {"group": "endo"}, "epi": {"group": "epi"},
                 "axis": [0, 0, 1], "endo_angle": 60, "epi_angle": -60},
      "integrator": "BackwardEuler", "predictor": "constant_acceleration", "density": 1060,
      "gravity": [0, 0, 0],
      "linear_solver": {"type": "cholmod"},
      "newton": {"tolerance": 1e-6, "max_iterations": 40, "reuse_factorization": true},
      "cavities": {"lumen": {"group": "endo"}},
      "boundary_conditions": [{"name": "base", "region": {"group": "base"}, "fix": true}]
    },
    "blood": {
      "type": "Circulation", "preset": "closed_loop", "dt": "5 ms", "log_events": false,
      "compartments": {"lv": {"driven_by": "pressure", "volume": "60 mL", "pressure": "0 mmHg"}},
      "connections": {"peripheral": {"resistance": "1.1 mmHg*s/mL"}}
    }
  },
  "connectors": {
    "excitation_contraction": {"type": "ExcitationContraction", "from": "bioelectricity.V",
                               "to": "muscle.nodal_active_tension", "gain": "115 kPa"},
    "cavity_coupling": {"type": "CavityCoupling", "wall": "muscle", "cavity": "lumen",
                        "blood": "blood", "chamber": "lv", "blood_bulk_modulus": "20 MPa"}
  },
  "order": ["bioelectricity", "excitation_contraction", "muscle", "cavity_coupling", "blood"],
  "monitor": {"blood": "blood", "chamber": "lv", "artery": "aorta", "period": "0.8 s"}
})";

/// `"muscle_model": "mass_spring"`: the muscle part becomes a MassSpring on the same mesh, with
/// the same fibres, cavity and held base, and every part steps at its 0.1 ms (the explicit wall
/// solves its cavity pressure with the blood each of its steps, so the blood steps with it).
/// Springs of 11 N/m with the exponential law b = 10 and a volume term of 50 kPa (the Guccione
/// law's bulk modulus): fitted to the Guccione ventricle's static pressure–volume curve
/// (docs/heart.md: within 0.4 mL from 2 to 12 mmHg, 1 mL at 15). Drag 100 /s and spring damping
/// 0.002 N·s/m damp the wall's ringing; 0.1 ms is 40 % of the explicit stability estimate at
/// rest (0.25 ms), a margin for the springs' stiffening with filling.
constexpr const char* kMassSpringMuscle = R"({
  "type": "MassSpring", "domain": "lv", "dt": "0.1 ms",
  "stiffness": 11, "material": {"law": "Exponential", "b": 10}, "volume_stiffness": 50000,
  "density": 1060, "drag": 100, "damping": 0.002, "gravity": [0, 0, 0],
  "fibres": {"rule": "transmural", "endo": {"group": "endo"}, "epi": {"group": "epi"},
             "axis": [0, 0, 1], "endo_angle": 60, "epi_angle": -60},
  "cavities": {"lumen": {"group": "endo"}},
  "boundary_conditions": [{"name": "base", "region": {"group": "base"}, "fix": true}]
})";

/// What else the mass-spring variant changes in the defaults (a merge patch).
constexpr const char* kMassSpringPatch = R"({
  "dt": "0.1 ms",
  "parts": {"blood": {"dt": "0.1 ms"}}
})";

/// `"muscle_model": "mixed"`: the muscle part becomes a MixedSolid (Taylor–Hood P2–P1, fully
/// incompressible: docs/incompressible.md) on the same mesh, with the same law, fibres, cavity,
/// held base, scheme and Newton settings; UMFPACK factorises its saddle-point tangent. The
/// excitation-contraction connector then writes the element field "active_tension" (MixedSolid
/// has no nodal one). The law's bulk modulus is not used (J = 1).
constexpr const char* kMixedMuscle = R"({
  "type": "MixedSolid", "domain": "lv", "dt": "5 ms",
  "material": {"law": "Guccione", "C": 1000, "bf": 8, "bt": 2, "bfs": 4, "bulk_modulus": 50000},
  "incompressible": true,
  "fibres": {"rule": "transmural", "endo": {"group": "endo"}, "epi": {"group": "epi"},
             "axis": [0, 0, 1], "endo_angle": 60, "epi_angle": -60},
  "integrator": "BackwardEuler", "predictor": "constant_acceleration", "density": 1060,
  "linear_solver": {"type": "umfpack"},
  "newton": {"tolerance": 1e-6, "max_iterations": 40, "reuse_factorization": true},
  "cavities": {"lumen": {"group": "endo"}},
  "boundary_conditions": [{"name": "base", "region": {"group": "base"}, "fix": true}]
})";

constexpr const char* kMixedPatch = R"({
  "connectors": {"excitation_contraction": {"to": "muscle.active_tension"}}
})";

}  // namespace

Heart::Heart(std::string name, Coordinator parts, HeartMonitorSpec monitor)
    : AggregateObject(std::move(name), std::move(parts)), monitor_(std::move(monitor)) {
  blood_ = FindPart(monitor_.blood);
  if (blood_ == nullptr)
    throw InputError(
        fmt::format("heart '{}': no part '{}' to monitor", this->path(), monitor_.blood));
  chamber_volume_ = blood_->FindField(monitor_.chamber + "_volume");
  chamber_pressure_ = blood_->FindField(monitor_.chamber + "_pressure");
  artery_pressure_ = blood_->FindField(monitor_.artery + "_pressure");
  if (!(monitor_.period > 0))
    throw InputError(fmt::format("heart '{}': the beat period must be positive", this->path()));
  BindAggregateState(state_);
  first_own_field_ = num_part_fields();
  using L = FieldLocation;
  using A = FieldAccess;
  const FieldInfo own[] = {
      {"beats", L::kGlobal, 1, "1", A::kRead, "completed beats"},
      {"end_diastolic_volume", L::kGlobal, 1, "m3", A::kRead, "EDV of the last completed beat"},
      {"end_systolic_volume", L::kGlobal, 1, "m3", A::kRead, "ESV of the last completed beat"},
      {"stroke_volume", L::kGlobal, 1, "m3", A::kRead, "EDV - ESV of the last completed beat"},
      {"ejection_fraction", L::kGlobal, 1, "1", A::kRead, "SV / EDV of the last completed beat"},
      {"peak_chamber_pressure", L::kGlobal, 1, "Pa", A::kRead, "of the last completed beat"},
      {"arterial_systolic_pressure", L::kGlobal, 1, "Pa", A::kRead, "of the last completed beat"},
      {"arterial_diastolic_pressure", L::kGlobal, 1, "Pa", A::kRead, "of the last completed beat"},
      {"cycle_change", L::kGlobal, 1, "1", A::kRead,
       "largest relative change of the last beat's figures from the beat before it"},
  };
  // The beat figures have no value before the first beat is complete, nor the change before
  // the second: they read -1, which probes, plots and the viewer show as "no data".
  for (FieldInfo info : own) {
    if (info.name != "beats") info.no_data = kNoBeat;
    DeclareField(info);
  }
}

StepStatus Heart::DoStep(double t, double dt) {
  StepStatus status = AggregateObject::DoStep(t, dt);
  if (status.ok()) Track(t + dt);
  return status;
}

void Heart::Track(double t) {
  Eigen::Matrix<double, 1, 1> v, p, a;
  blood_->ReadField(chamber_volume_, v);
  blood_->ReadField(chamber_pressure_, p);
  blood_->ReadField(artery_pressure_, a);
  HeartMonitorState& m = state_;
  if (!m.beat_started) {
    m.v_max = m.v_min = v(0, 0);
    m.p_max = p(0, 0);
    m.a_max = m.a_min = a(0, 0);
    m.beat_started = true;
  } else {
    m.v_max = std::max(m.v_max, v(0, 0));
    m.v_min = std::min(m.v_min, v(0, 0));
    m.p_max = std::max(m.p_max, p(0, 0));
    m.a_max = std::max(m.a_max, a(0, 0));
    m.a_min = std::min(m.a_min, a(0, 0));
  }
  if (t >= (m.beat_index + 1) * monitor_.period - 1e-9 * monitor_.period) {
    FinishBeat(t);
    // The beat's last sample opens the next one (it is both end-diastolic and first).
    m.v_max = m.v_min = v(0, 0);
    m.p_max = p(0, 0);
    m.a_max = m.a_min = a(0, 0);
  }
}

void Heart::FinishBeat(double t) {
  HeartMonitorState& m = state_;
  BeatSummary beat;
  beat.beat = ++m.beat_index;
  beat.end_time = t;
  beat.edv = m.v_max;
  beat.esv = m.v_min;
  beat.peak_pressure = m.p_max;
  beat.arterial_systolic = m.a_max;
  beat.arterial_diastolic = m.a_min;
  const std::vector<BeatSummary>& beats = m.beats.get();
  if (!beats.empty()) {
    const BeatSummary& prev = beats.back();
    auto rel = [](double x, double y) { return std::abs(x - y) / std::max(std::abs(x), 1e-300); };
    beat.change = std::max({rel(beat.edv, prev.edv), rel(beat.esv, prev.esv),
                            rel(beat.peak_pressure, prev.peak_pressure),
                            rel(beat.arterial_systolic, prev.arterial_systolic),
                            rel(beat.arterial_diastolic, prev.arterial_diastolic)});
  }
  m.beats.Write().push_back(beat);
  constexpr double kMl = 1e6, kMmHg = 1.0 / 133.322387415;
  Log().info(
      "{}: beat {} ({:.3f} s): EDV {:.1f} mL, ESV {:.1f} mL, SV {:.1f} mL, EF {:.1f} %, peak {} "
      "pressure {:.1f} mmHg, {} {:.1f}/{:.1f} mmHg, change from the previous beat {}",
      path(), beat.beat, t, kMl * beat.edv, kMl * beat.esv, kMl * beat.stroke_volume(),
      100 * beat.ejection_fraction(), monitor_.chamber, kMmHg * beat.peak_pressure, monitor_.artery,
      kMmHg * beat.arterial_systolic, kMmHg * beat.arterial_diastolic,
      beats.size() == 1 ? std::string("—")  // no previous beat to compare with
                        : fmt::format("{:.2f} %", 100 * beat.change));
}

void Heart::DoReadField(FieldId id, Eigen::Ref<Eigen::MatrixXd> out) const {
  const auto index = static_cast<std::size_t>(id.value());
  if (index < first_own_field_) {
    AggregateObject::DoReadField(id, out);
    return;
  }
  const std::vector<BeatSummary>& beats = state_.beats.get();
  if (index > first_own_field_ && beats.empty()) {  // no completed beat: no figures yet
    out(0, 0) = kNoBeat;
    return;
  }
  const BeatSummary last = beats.empty() ? BeatSummary{} : beats.back();
  switch (index - first_own_field_) {
    case 0:
      out(0, 0) = static_cast<double>(beats.size());
      break;
    case 1:
      out(0, 0) = last.edv;
      break;
    case 2:
      out(0, 0) = last.esv;
      break;
    case 3:
      out(0, 0) = last.stroke_volume();
      break;
    case 4:
      out(0, 0) = last.ejection_fraction();
      break;
    case 5:
      out(0, 0) = last.peak_pressure;
      break;
    case 6:
      out(0, 0) = last.arterial_systolic;
      break;
    case 7:
      out(0, 0) = last.arterial_diastolic;
      break;
    default:
      out(0, 0) = last.change;
      break;
  }
}

void Heart::DoWriteField(FieldId id, const Eigen::Ref<const Eigen::MatrixXd>& in) {
  // Only the parts' writable fields reach here (the monitor's are read-only).
  AggregateObject::DoWriteField(id, in);
}

void RegisterHeart(TypeRegistry& registry) {
  registry.objects.Register(
      "Heart",
      [](const ObjectBuildContext& ctx) -> std::unique_ptr<SimObject> {
        ctx.CheckKeys({"parts", "connectors", "order", "monitor", "muscle_model"});
        // The scene patches the defaults (RFC 7386): change one parameter
        // ("parts": {"muscle": {"material": {"C": 800}}}), replace a part, or drop one with null.
        auto merged = nlohmann::ordered_json::parse(kHeartDefaults);
        nlohmann::ordered_json patch = ctx.params.raw();
        for (const std::string& key : ObjectBuildContext::CommonKeys())
          if (key != "dt") patch.erase(key);
        std::string muscle_model = "fem";
        if (auto model = ctx.params.Find("muscle_model"))
          muscle_model = model->AsChoice({"fem", "mass_spring", "mixed"});
        patch.erase("muscle_model");
        if (muscle_model == "mass_spring") {
          merged["parts"]["muscle"] = nlohmann::ordered_json::parse(kMassSpringMuscle);
          merged.merge_patch(nlohmann::ordered_json::parse(kMassSpringPatch));
        } else if (muscle_model == "mixed") {
          merged["parts"]["muscle"] = nlohmann::ordered_json::parse(kMixedMuscle);
          merged.merge_patch(nlohmann::ordered_json::parse(kMixedPatch));
        }
        merged.merge_patch(patch);
        const JsonNode root(
            merged, fmt::format("{} (heart defaults patched by the scene)", ctx.params.file()),
            ctx.params.path());
        HeartMonitorSpec monitor;
        const JsonNode m = root.At("monitor");
        m.CheckKeys({"blood", "chamber", "artery", "period"});
        monitor.blood = m.At("blood").AsString();
        monitor.chamber = m.At("chamber").AsString();
        monitor.artery = m.At("artery").AsString();
        monitor.period = ReadPositiveQuantity(m.At("period"), "s");
        Coordinator parts = BuildAggregateParts(ctx, root);
        // The cavity coupling fires once per macro step between the wall's step and the
        // blood's, so both must step exactly once per macro step.
        for (std::size_t i = 0; i < parts.num_objects(); ++i) {
          const std::string& part = parts.object(i).name();
          if ((part == "muscle" || part == "blood") && parts.object_substeps(i) != 1)
            root.At("dt").Fail(fmt::format(
                "the heart's dt ({} s) must equal its {}'s dt ({} s): the cavity coupling "
                "solves the wall together with the blood once per macro step",
                parts.macro_dt(), part, parts.object_dt(i)));
        }
        try {
          return std::make_unique<Heart>(ctx.name, std::move(parts), monitor);
        } catch (const InputError& e) {
          m.Fail(e.what());
        }
      },
      "the GiPSi heart: bioelectricity + muscle + blood with their connectors (defaults: a left "
      "ventricle), and a beat monitor (EDV, ESV, EF, pressures)");
}

}  // namespace gipsi
