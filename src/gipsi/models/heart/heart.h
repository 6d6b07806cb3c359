#pragma once
/// @file
/// `Heart`: the GiPSi paper's test-bed as one reusable object type — an aggregate of
/// bioelectricity (Monodomain), muscle (FemSolid, Guccione myocardium with active tension) and
/// blood (lumped closed-loop Circulation), coupled by an ExcitationContraction connector
/// (voltage → active tension, through the shared volume) and a CavityCoupling connector
/// (endocardial volume ↔ cavity pressure, through the shared boundary). Its parts and connectors
/// come from a default document (`kHeartDefaults` in heart.cc: a left ventricle on the mesh
/// named "lv") that the scene patches key by key (RFC 7386), like the circulation's presets.
///
/// On top of the aggregate it monitors the beats: per beat of `monitor.period` seconds, the
/// end-diastolic and end-systolic volumes (the beat's largest and smallest chamber volume),
/// stroke volume, ejection fraction, peak chamber pressure, arterial systolic and diastolic
/// pressure, and the largest relative change of these from the previous beat (how close the
/// run is to its periodic state). They are global fields (of the last completed beat) and a
/// line in the log per beat.

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "gipsi/base/export.h"
#include "gipsi/core/aggregate.h"
#include "gipsi/core/registry.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// Which blood fields the monitor reads. Plain struct.
struct HeartMonitorSpec {
  std::string blood = "blood";   ///< the blood part
  std::string chamber = "lv";    ///< its chamber compartment (volume and pressure)
  std::string artery = "aorta";  ///< its arterial compartment (pressure)
  double period = 0.8;           ///< beat length [s]; beats start at t = 0
};

/// What the beat monitor's fields read when there is no value yet (before the first completed
/// beat; for `cycle_change`, before the second): their FieldInfo::no_data marker.
inline constexpr double kNoBeat = -1;

/// One completed beat. Plain struct (SI units).
struct BeatSummary {
  int beat = 0;                   ///< 1, 2, …
  double end_time = 0;            ///< [s]
  double edv = 0;                 ///< end-diastolic volume [m³]
  double esv = 0;                 ///< end-systolic volume [m³]
  double peak_pressure = 0;       ///< chamber [Pa]
  double arterial_systolic = 0;   ///< [Pa]
  double arterial_diastolic = 0;  ///< [Pa]
  /// Largest relative change of the above from the previous beat; kNoBeat for the first beat.
  double change = kNoBeat;
  [[nodiscard]] double stroke_volume() const { return edv - esv; }
  [[nodiscard]] double ejection_fraction() const { return edv > 0 ? (edv - esv) / edv : 0; }
  template <class Self, class V>
  static void Fields(Self& s, V& v) {
    v("beat", s.beat);
    v("end_time", s.end_time);
    v("edv", s.edv);
    v("esv", s.esv);
    v("peak_pressure", s.peak_pressure);
    v("arterial_systolic", s.arterial_systolic);
    v("arterial_diastolic", s.arterial_diastolic);
    v("change", s.change);
  }
};

/// What the beat monitor carries from one step to the next (a state value type,
/// gipsi/base/state_value.h): the completed beats (copied only when one was added) and the
/// beat in progress.
struct HeartMonitorState {
  static constexpr std::string_view kTag = "HeartMonitor";
  static constexpr std::uint32_t kVersion = 2;
  Stamped<std::vector<BeatSummary>> beats;
  // Running extremes of the beat in progress.
  double v_max = 0, v_min = 0, p_max = 0, a_max = 0, a_min = 0;
  bool beat_started = false;
  int beat_index = 0;  // of the beat in progress
  template <class Self, class V>
  static void Fields(Self& s, V& v) {
    v("beats", s.beats);
    v("v_max", s.v_max);
    v("v_min", s.v_min);
    v("p_max", s.p_max);
    v("a_max", s.a_max);
    v("a_min", s.a_min);
    v("beat_started", s.beat_started);
    v("beat_index", s.beat_index);
  }
};

/// Not copyable or movable (a SimObject).
class Heart final : public AggregateObject {
 public:
  /// Throws InputError if the monitored blood part, chamber or artery does not exist.
  Heart(std::string name, Coordinator parts, HeartMonitorSpec monitor);

  [[nodiscard]] std::string_view type_name() const override { return "Heart"; }
  /// Every completed beat so far.
  [[nodiscard]] const std::vector<BeatSummary>& beats() const { return state_.beats.get(); }
  /// The monitor's state (bound with BindAggregateState: checkpoints and snapshots copy it).
  [[nodiscard]] const HeartMonitorState& monitor_state() const { return state_; }

 protected:
  StepStatus DoStep(double t, double dt) override;
  void DoReadField(FieldId id, Eigen::Ref<Eigen::MatrixXd> out) const override;
  void DoWriteField(FieldId id, const Eigen::Ref<const Eigen::MatrixXd>& in) override;

 private:
  void Track(double t);
  void FinishBeat(double t);

  HeartMonitorSpec monitor_;
  SimObject* blood_ = nullptr;
  FieldId chamber_volume_, chamber_pressure_, artery_pressure_;
  HeartMonitorState state_;
  std::size_t first_own_field_ = 0;
};

/// Registers "Heart" (keys in docs/scene-format.md and docs/heart.md).
void RegisterHeart(TypeRegistry& registry);

}  // namespace gipsi
GIPSI_EXPORT_END
