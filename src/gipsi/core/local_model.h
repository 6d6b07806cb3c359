#pragma once
/// @file
/// The local model an object provides for haptics (the GiPSi paper's multi-rate haptics):
/// the model's data, its discretisation and the `LocalModelBuilder` interface an object type
/// implements and registers (`LocalModels(registry)`, beside the type's own registration).
/// The haptic side that steps these models is gipsi/haptics/local_model.h.
///
/// Local dynamic models for multi-rate haptics (Çavuşoğlu & Tendick, ICRA 2000): a low-order
/// linear model of an object around the contact node, built by the object at its own rate,
/// already discretised for the haptic period, and published to the haptic loop through a
/// `LatestValue` buffer. A tick is then a few small matrix–vector products.
///
/// The model. Local degrees of freedom u (3m: the contact node first, then the other moving
/// nodes) are displacements from the anchor (the object's state when the model was built),
/// with velocities v. With P the unit vector selecting the contact node's displacement along
/// the inward normal −n, the tool pushes the contact node with a normal force F ≥ 0:
///   M u'' + C u' + K u = q + F P,
/// where M (lumped, diagonal), C, K are the object's mass, damping and tangent stiffness
/// restricted to the local nodes (the ring around them held fixed), and q is the constant load
/// that makes the model reproduce the object's acceleration at the anchor with the anchor's tool
/// force F0 (q = M a0 + C v0 − F0 P). Backward Euler with the haptic period h gives
///   v⁺ = S⁻¹ (M v / h − K u + q + F P),  u⁺ = u + h v⁺,  S = M/h + C + h K,
/// precomputed as v⁺ = A_v v + A_u u + a + F g with g = S⁻¹ P.
///
/// The geometric model is the tangent plane through the anchor position of the contact node
/// with outward normal n; the device's depth below it is d = (point − x)·n. The device reaches
/// the contact node through a virtual coupling (a spring k_c and damper b_c in the normal
/// direction, compression only), solved implicitly with the step, so
///   F = max(0, [k_c (d − y_f) + b_c (d' − y'_f)] / (1 + (k_c h + b_c) c)),  c = Pᵀ g,
/// where y_f = Pᵀ u⁺ and y'_f = Pᵀ v⁺ of the free step (F = 0). The god-object (proxy) is the
/// contact node's surface point: it never goes below the local surface, and the device force is
/// F n. A large k_c makes the proxy follow the device; a finite one bounds the stiffness the
/// device feels (the sampled-data passivity condition, Colgate & Schenkel 1997, needs the
/// device's own damping above k h / 2).

#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

#include "gipsi/base/export.h"
#include "gipsi/base/math.h"
#include "gipsi/core/registry.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

class SimObject;

/// Most nodes a local model may have (the contact node included).
inline constexpr int kMaxLocalNodes = 20;
/// Most degrees of freedom of a local model.
inline constexpr int kMaxLocalDofs = 3 * kMaxLocalNodes;
/// Dense matrix with inline storage for up to kMaxLocalDofs square: never allocates.
using LocalMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::ColMajor,
                                  kMaxLocalDofs, kMaxLocalDofs>;
/// Vector with inline storage for up to kMaxLocalDofs entries: never allocates.
using LocalVector = Eigen::Matrix<double, Eigen::Dynamic, 1, Eigen::ColMajor, kMaxLocalDofs, 1>;

/// A published local model: geometry (tangent plane) and dynamics (discretised). Plain struct;
/// copyable without allocation.
struct LocalDynamicModel {
  bool active = false;           ///< false: no contact possible (free motion, zero force)
  double published_at = -1e300;  ///< simulation time of publication [s]
  double period = 1e-3;          ///< haptic period h the model is discretised for [s]
  Vec3 point = Vec3::Zero();     ///< contact node position at the anchor [m]
  Vec3 normal = Vec3::UnitZ();   ///< outward unit normal at the contact node
  double anchor_force = 0;       ///< normal tool force F0 at the anchor [N]
  int contact_vertex = -1;       ///< boundary vertex of the contact node (object numbering)
  int num_nodes = 0;             ///< m, local nodes (contact node first)
  // Discretised step (3m unknowns).
  LocalMatrix step_v;            ///< A_v = S⁻¹ M / h
  LocalMatrix step_u;            ///< A_u = −S⁻¹ K
  LocalVector step_bias;         ///< a = S⁻¹ q [m/s]
  LocalVector gain;              ///< g = S⁻¹ P [m/(N s)]
  LocalVector push;              ///< P, inward unit normal on the contact node's three dofs
  double compliance = 0;         ///< c = Pᵀ g [m/(N s)]
  LocalVector initial_velocity;  ///< v at the anchor (the object's node velocities) [m/s]
  // For energy bookkeeping (tests, diagnostics).
  LocalMatrix stiffness;  ///< K [N/m]
  LocalVector mass;       ///< diagonal of M per dof [kg]
  LocalVector load;       ///< q [N]

  [[nodiscard]] int dofs() const { return 3 * num_nodes; }
  template <class Self, class V>
  static void Fields(Self& s, V& v) {
    v("active", s.active);
    v("published_at", s.published_at);
    v("period", s.period);
    v("point", s.point);
    v("normal", s.normal);
    v("anchor_force", s.anchor_force);
    v("contact_vertex", s.contact_vertex);
    v("num_nodes", s.num_nodes);
    v("step_v", s.step_v);
    v("step_u", s.step_u);
    v("step_bias", s.step_bias);
    v("gain", s.gain);
    v("push", s.push);
    v("compliance", s.compliance);
    v("initial_velocity", s.initial_velocity);
    v("stiffness", s.stiffness);
    v("mass", s.mass);
    v("load", s.load);
  }
};

/// Builds the discretised model from M (diagonal, per dof), C, K (3m square), the anchor
/// velocities v0 and acceleration a0 (3m), the anchor's normal tool force F0, the contact
/// node's position and outward normal, and the haptic period h. The contact node is local
/// node 0. Sizes must agree and not exceed kMaxLocalDofs (checked). Returns false (leaving
/// `out` inactive) if the step matrix S is singular or a value is not finite. Runs on the
/// simulation side (allocates).
bool DiscretiseLocalModel(const VecX& mass, const Eigen::MatrixXd& damping,
                          const Eigen::MatrixXd& stiffness, const VecX& v0, const VecX& a0,
                          double anchor_force, const Vec3& point, const Vec3& normal, double period,
                          LocalDynamicModel& out);

/// Builds local models of one object at its current state. Not copyable; runs on the
/// simulation thread only.
class LocalModelBuilder {
 public:
  LocalModelBuilder() = default;
  LocalModelBuilder(const LocalModelBuilder&) = delete;
  LocalModelBuilder& operator=(const LocalModelBuilder&) = delete;
  virtual ~LocalModelBuilder() = default;

  /// The object the models describe.
  [[nodiscard]] virtual SimObject& object() = 0;
  /// Builds the model for contact at boundary vertex `vertex` with outward unit `normal`, the
  /// tool pushing with normal force `anchor_force` [N] at the current state, discretised for
  /// the haptic `period` [s]. Returns false (model inactive) if the vertex is constrained or
  /// the linearisation is singular.
  virtual bool Build(Index vertex, const Vec3& normal, double anchor_force, double period,
                     LocalDynamicModel& out) = 0;
};

/// Builds the haptic local-model builder of an object of the type it is registered under;
/// `rings` is the HapticCoupling's neighbourhood size (0-5), for builders that use one. May
/// throw InputError (e.g. an object without a boundary).
using LocalModelFactory =
    std::function<std::unique_ptr<LocalModelBuilder>(SimObject& object, int rings)>;

/// The haptic local models, keyed by the object type (SimObject::type_name()) they describe: a
/// HapticCoupling can render any object whose type has one. A model type registers its own
/// beside its object factory (plugins too).
inline FactoryTable<LocalModelFactory>& LocalModels(TypeRegistry& registry) {
  return registry.Table<LocalModelFactory>("haptic local model");
}
inline const FactoryTable<LocalModelFactory>& LocalModels(const TypeRegistry& registry) {
  return registry.Table<LocalModelFactory>("haptic local model");
}

/// Per domain node of `object`: 1 if any axis of its boundary vertex is constrained (such nodes
/// are held fixed in local models), else 0.
[[nodiscard]] std::vector<std::uint8_t> ConstrainedNodes(const SimObject& object);

}  // namespace gipsi
GIPSI_EXPORT_END
