#pragma once
/// @file
/// `ExcitationContraction`: the bioelectricity → muscle coupling of the GiPSi heart through the
/// shared volume. It Gets the transmembrane voltage V [mV] of an electrophysiology object,
/// interpolates it at the items of the muscle's active-tension field (nodes or element
/// centroids, on another mesh if need be), drives a first-order active-tension model there, and
/// Sets the tension T_a [Pa] (acting along the fibres) on the muscle.
///
/// The model is of the Nash–Panfilov type (Nash & Panfilov, Prog. Biophys. Mol. Biol. 85:501,
/// 2004): with the normalised excitation u = (V − v_rest)/(v_peak − v_rest) clamped to [0, 1],
///   dT_a/dt = ε(u) (k u − T_a),   ε = rise_rate while u ≥ threshold, decay_rate below it,
/// so tension builds up during the action potential and relaxes after repolarisation. V is held
/// at its value at the firing time over the interval since the previous firing, and the linear
/// ODE is integrated exactly: T_a ← k u + (T_a − k u) e^{−ε Δt} (stable for any interval).
/// T_a is the muscle's: each firing reads the tension field back and relaxes it from its current
/// value (what the connector last Set, unless something else wrote it since), so the tension's
/// state is checkpointed, restored and moved with the muscle; the connector keeps only its clock.
///
/// When the electrophysiology and the muscle are split alike over the processes of a
/// distributed run (SplitAlike: one mesh, one cut), each process couples its own parts: it reads
/// its part's V, takes the values of the nodes it shares from their owners
/// (ShareOwnedNodeValues, O(the part's surface)), and writes its part's tension. No process
/// gathers a whole field, and every item gets the value the whole-field path would give it.
/// Split any other way (the muscle on another mesh, or one of them whole on every process), the
/// muscle's items are this process's own (its part's, or all of a whole muscle), and a split
/// EP object's parts answer for them (PartitionedObject::InterpolateAtPoints): no process
/// gathers V either.
///
/// Units: V in mV (the EP objects' unit); k in Pa; rates in 1/s; kernel time in s.

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <string_view>

#include "gipsi/base/export.h"
#include "gipsi/core/connector.h"
#include "gipsi/core/partitioned_object.h"
#include "gipsi/core/registry.h"
#include "gipsi/core/sim_object.h"
#include "gipsi/geometry/mapping.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// Parameters. Plain struct with defaults (a demonstration twitch: about 40 kPa after 300 ms of
/// excitation, relaxing with a 33 ms time constant; not fitted to data).
struct ExcitationContractionParams {
  double v_rest = -80;       ///< mV: u = 0
  double v_peak = 20;        ///< mV: u = 1
  double threshold = 0.05;   ///< u at which the rate switches
  double gain = 5e4;         ///< k [Pa]: the tension approached under full excitation
  double rise_rate = 5.0;    ///< 1/s
  double decay_rate = 30.0;  ///< 1/s
};

/// What ExcitationContraction carries from one firing to the next (a state value type,
/// gipsi/base/state_value.h). Version 2: the tension is the muscle's (version 1 kept a copy).
struct ExcitationContractionState {
  static constexpr std::string_view kTag = "ExcitationContractionState";
  static constexpr std::uint32_t kVersion = 2;
  double last_time = 0;  ///< when it last fired [s]
  bool fired = false;    ///< whether it has fired (the first firing integrates over 0 s)
  template <class Self, class V>
  static void Fields(Self& s, V& v) {
    v("last_time", s.last_time);
    v("fired", s.fired);
  }
};

/// Not copyable or movable (a Connector).
class ExcitationContraction final : public Connector {
 public:
  /// `voltage` must be a readable scalar node field of `ep`; `tension` a readable and writable
  /// scalar node or element field of `muscle`. Throws InputError otherwise, or for bad
  /// parameters. Collective over the processes of a distributed run when either object is
  /// split.
  ExcitationContraction(std::string name, const SimObject& ep, FieldId voltage, SimObject& muscle,
                        FieldId tension, const ExcitationContractionParams& params);

  [[nodiscard]] std::string_view type_name() const override { return "ExcitationContraction"; }
  /// The state (bound with BindState: checkpoints and snapshots copy it).
  [[nodiscard]] const ExcitationContractionState& state() const { return state_; }
  /// Whether it couples the objects' parts, process by process (split alike, or any way).
  [[nodiscard]] bool couples_parts() const override {
    return agree_on_ != nullptr || interpolation_ != nullptr;
  }

 protected:
  StepStatus DoFire(double t) override;

 private:
  // The objects read and written: the scene's, or their parts when they are split alike.
  const SimObject* ep_;
  FieldId voltage_;
  SimObject* muscle_;
  FieldId tension_field_;
  const PartitionedObject* split_ = nullptr;  // the split EP object, when coupling parts alike
  // The split object whose part the muscle's items are (they agree on a failure).
  const PartitionedObject* agree_on_ = nullptr;
  // A split EP object's V interpolated at the muscle's items by the parts that hold them.
  std::unique_ptr<PartsInterpolation> interpolation_;
  FieldLocation tension_location_ = FieldLocation::kNode;
  ExcitationContractionParams params_;
  std::optional<PointMap> map_;  // empty: the items coincide
  Eigen::MatrixXd source_, mapped_, tension_;
  ExcitationContractionState state_;
};

/// Registers "ExcitationContraction" (keys in docs/scene-format.md).
void RegisterExcitationContraction(TypeRegistry& registry);

}  // namespace gipsi
GIPSI_EXPORT_END
