/// @file
/// FemSolid's state as rows per item (RowState, core/row_state.h), to move a split solid's part
/// to another partition: per node the scheme's displacements, velocities and their history, the
/// previous step's nodal loads, the external force and the nodal active tension; per tet the
/// active tension and the material axes; per boundary face the previous step's pressure and
/// traction; and the rest (the scheme's clock and kind, the cavities, the last Jacobian norm and
/// Newton statistics), which every part of one solid holds alike, as bytes. The Newton solver's
/// cache (warm start, kept factorisation) is not moved: the first solve after the move starts
/// afresh, which changes the bits of the answer within Newton's tolerance.

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <string_view>
#include <type_traits>

#include "gipsi/base/error.h"
#include "gipsi/base/state_binding.h"
#include "gipsi/models/fem/fem_solid.h"

namespace gipsi {
namespace {

// The scheme's fields by name, through its state-value field list (ImplicitScheme::Fields).
struct SchemeFields {
  VecX *x = nullptr, *v = nullptr, *a = nullptr, *dx_prev = nullptr, *v_prev = nullptr;
  double *dt_prev = nullptr, *dt = nullptr;
  bool* bdf2_now = nullptr;
  ImplicitSchemeKind* kind = nullptr;

  explicit SchemeFields(ImplicitScheme& scheme) { ImplicitScheme::Fields(scheme, *this); }
  template <class T>
  void operator()(std::string_view name, T& field, Shape /*shape*/ = Shape::kAny) {
    if constexpr (std::is_same_v<T, VecX>) {
      (name == "x"         ? x
       : name == "v"       ? v
       : name == "a"       ? a
       : name == "dx_prev" ? dx_prev
                           : v_prev) = &field;
    } else if constexpr (std::is_same_v<T, double>) {
      (name == "dt_prev" ? dt_prev : dt) = &field;
    } else if constexpr (std::is_same_v<T, bool>) {
      bdf2_now = &field;
    } else {
      static_assert(std::is_same_v<T, ImplicitSchemeKind>, "a new ImplicitScheme field");
      kind = &field;
    }
  }
  // The 3-per-node vectors in row order: x, v, then a, dx_prev, v_prev where present.
  [[nodiscard]] std::vector<VecX*> PerNode(const std::array<bool, 3>& present) const {
    std::vector<VecX*> out{x, v};
    if (present[0]) out.push_back(a);
    if (present[1]) out.push_back(dx_prev);
    if (present[2]) out.push_back(v_prev);
    return out;
  }
};

}  // namespace

StateRows FemSolid::ReadStateRows(StateReader& in, const ItemCounts& counts) const {
  // A state of the other part's sizes (its kind, cavities and statistics as this one's), read
  // with the bound state's own reader; then the Newton cache, skipped.
  const auto n = static_cast<Index>(counts.nodes), e = static_cast<Index>(counts.tets),
             f = static_cast<Index>(counts.faces);
  FemState read = state_;
  read.scheme.Reset(VecX::Zero(3 * n), VecX::Zero(3 * n), VecX::Zero(3 * n));
  read.f_nodal_prev = VecX::Zero(3 * n);
  read.pressure_prev = VecX::Zero(f);
  read.traction_prev = Points::Zero(3, f);
  read.external_force.Write() = Points::Zero(3, n);
  read.active_tension = VecX::Zero(e);
  read.nodal_active_tension = VecX::Zero(n);
  read.axes.Write().clear();
  BindStateValue(read)->Read(in, {});
  in.SkipRestOfSection();

  SchemeFields scheme(read.scheme);
  const std::array<bool, 3> present{scheme.a->size() > 0, scheme.dx_prev->size() > 0,
                                    scheme.v_prev->size() > 0};
  for (const VecX* h : {scheme.a, scheme.dx_prev, scheme.v_prev})
    if (h->size() != 0 && h->size() != 3 * n)
      in.Fail(fmt::format("a scheme history of {} values for {} nodes", h->size(), n));
  const std::vector<VecX*> per_node = scheme.PerNode(present);
  const bool axes = !read.axes.get().empty();
  if (axes && static_cast<Index>(read.axes.get().size()) != e)
    in.Fail(fmt::format("{} material axes for {} tets", read.axes.get().size(), e));

  StateRows rows;
  rows.node_width = 3 * static_cast<int>(per_node.size()) + 7;
  rows.tet_width = axes ? 10 : 1;
  rows.face_width = 4;
  rows.node.reserve(static_cast<std::size_t>(n * rows.node_width));
  for (Index i = 0; i < n; ++i) {
    for (const VecX* vec : per_node)
      for (int k = 0; k < 3; ++k) rows.node.push_back((*vec)[3 * i + k]);
    for (int k = 0; k < 3; ++k) rows.node.push_back(read.f_nodal_prev[3 * i + k]);
    for (int k = 0; k < 3; ++k) rows.node.push_back(read.external_force.get()(k, i));
    rows.node.push_back(read.nodal_active_tension[i]);
  }
  for (Index t = 0; t < e; ++t) {
    rows.tet.push_back(read.active_tension[t]);
    if (axes) {
      const Mat3& m = read.axes.get()[static_cast<std::size_t>(t)];
      rows.tet.insert(rows.tet.end(), m.data(), m.data() + 9);
    }
  }
  for (Index j = 0; j < f; ++j) {
    rows.face.push_back(read.pressure_prev[j]);
    for (int k = 0; k < 3; ++k) rows.face.push_back(read.traction_prev(k, j));
  }
  StateWriter shared;
  shared.WriteInt(static_cast<std::int64_t>(*scheme.kind));
  for (const bool p : present) shared.WriteBool(p);
  shared.WriteBool(axes);
  shared.WriteDouble(*scheme.dt_prev);
  shared.WriteDouble(*scheme.dt);
  shared.WriteBool(*scheme.bdf2_now);
  shared.WriteBool(read.have_prev_loads);
  shared.WriteBool(read.active_from_nodes);
  shared.WriteInt(static_cast<std::int64_t>(read.cavities.size()));
  for (const FemCavityState& c : read.cavities) WriteFields(shared, c);
  shared.WriteDouble(read.jacobian_norm);
  WriteFields(shared, read.last_newton);
  rows.shared = shared.TakeBytes();
  return rows;
}

void FemSolid::WriteStateRows(StateWriter& out, const StateRows& rows) const {
  const Index n = num_nodes(), e = num_elements(), f = boundary().num_triangles();
  FemState written = state_;  // this part's sizes; every per-item value replaced below
  StateReader shared(rows.shared, fmt::format("object '{}': the shared state", name()));
  SchemeFields scheme(written.scheme);
  if (static_cast<ImplicitSchemeKind>(shared.ReadInt()) != *scheme.kind)
    shared.Fail("another time scheme");
  std::array<bool, 3> present{};
  for (bool& p : present) p = shared.ReadBool();
  const bool axes = shared.ReadBool();
  *scheme.dt_prev = shared.ReadDouble();
  *scheme.dt = shared.ReadDouble();
  *scheme.bdf2_now = shared.ReadBool();
  written.have_prev_loads = shared.ReadBool();
  written.active_from_nodes = shared.ReadBool();
  if (shared.ReadInt() != static_cast<std::int64_t>(written.cavities.size()))
    shared.Fail("another number of cavities");
  for (FemCavityState& c : written.cavities) ReadFields(shared, c);
  written.jacobian_norm = shared.ReadDouble();
  ReadFields(shared, written.last_newton);
  if (!shared.at_end()) shared.Fail("more shared state than a FemSolid's");

  const std::array<VecX*, 3> history{scheme.a, scheme.dx_prev, scheme.v_prev};
  for (std::size_t h = 0; h < 3; ++h) {
    if (present[h])
      history[h]->setZero(3 * n);
    else
      history[h]->resize(0);
  }
  const std::vector<VecX*> per_node = scheme.PerNode(present);
  const int node_width = 3 * static_cast<int>(per_node.size()) + 7;
  const int tet_width = axes ? 10 : 1;
  if (rows.node_width != node_width || rows.tet_width != tet_width || rows.face_width != 4 ||
      static_cast<Index>(rows.node.size()) != n * node_width ||
      static_cast<Index>(rows.tet.size()) != e * tet_width ||
      static_cast<Index>(rows.face.size()) != f * 4)
    shared.Fail(
        fmt::format("rows of {}/{}/{} values per node/tet/face for {}/{}/{} items, where "
                    "this FemSolid's state has {}/{}/4",
                    rows.node_width, rows.tet_width, rows.face_width, rows.node.size(),
                    rows.tet.size(), rows.face.size(), node_width, tet_width));
  Points& external = written.external_force.Write();
  const double* row = rows.node.data();
  for (Index i = 0; i < n; ++i) {
    for (VecX* vec : per_node)
      for (int k = 0; k < 3; ++k) (*vec)[3 * i + k] = *row++;
    for (int k = 0; k < 3; ++k) written.f_nodal_prev[3 * i + k] = *row++;
    for (int k = 0; k < 3; ++k) external(k, i) = *row++;
    written.nodal_active_tension[i] = *row++;
  }
  std::vector<Mat3>& all_axes = written.axes.Write();
  all_axes.assign(axes ? static_cast<std::size_t>(e) : 0, Mat3::Identity());
  row = rows.tet.data();
  for (Index t = 0; t < e; ++t) {
    written.active_tension[t] = *row++;
    if (axes) {
      std::copy_n(row, 9, all_axes[static_cast<std::size_t>(t)].data());
      row += 9;
    }
  }
  row = rows.face.data();
  for (Index j = 0; j < f; ++j) {
    written.pressure_prev[j] = *row++;
    for (int k = 0; k < 3; ++k) written.traction_prev(k, j) = *row++;
  }
  BindStateValue(written)->Write(out);
  SaveStateCache(out);  // this part's, as it is before its first step: nothing kept
}

}  // namespace gipsi
