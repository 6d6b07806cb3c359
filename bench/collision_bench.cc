// Collision detection: refit + exact proximity query for two deforming, interpenetrating sheets
// (20k and 100k triangles each), and self-collision of one folded 20k sheet. One core.
// With FCL 0.7 installed (libfcl-dev), the same sheets through FCL's AABB BVH: refit
// (bottom-up) + collide (all intersecting triangle pairs), measured in the same run.

#include <benchmark/benchmark.h>

#include <cmath>
#include <numbers>

#include "gipsi/collision/collision_surface.h"
#include "gipsi/collision/proximity.h"
#include "gipsi/geometry/generators.h"

#ifdef GIPSI_HAVE_FCL
#include <fcl/fcl.h>
#endif

namespace gipsi {
namespace {

struct SheetPair {
  Mesh mesh_a, mesh_b;
  double cell = 0;
  explicit SheetPair(int n)
      : mesh_a(MakeTriangleSheet(Vec3::Zero(), Vec3(1, 0, 0), Vec3(0, 1, 0), {n, n})),
        mesh_b(
            MakeTriangleSheet(Vec3(0.37 / n, 0.61 / n, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), {n, n})),
        cell(1.0 / n) {}
  // Sheet a: z = A sin(6x + φ) cos(4y); sheet b: z = A cos(5x) sin(7y − φ). They cross along
  // curves and move every step.
  void Deform(int step, Points& xa, Points& xb) const {
    const double phase = 0.01 * step, amp = 0.05;
    for (Index v = 0; v < xa.cols(); ++v) {
      const double x = mesh_a.nodes(0, v), y = mesh_a.nodes(1, v);
      xa.col(v) << x, y, amp * std::sin(6 * x + phase) * std::cos(4 * y);
    }
    for (Index v = 0; v < xb.cols(); ++v) {
      const double x = mesh_b.nodes(0, v), y = mesh_b.nodes(1, v);
      xb.col(v) << x, y, amp * std::cos(5 * x) * std::sin(7 * y - phase);
    }
  }
};

// Cells per side: 100 → 20,000 triangles; 224 → 100,352.
void BM_GipsiSheets(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  SheetPair pair(n);
  CollisionSurface a(pair.mesh_a.triangles, pair.mesh_a.num_nodes(), false);
  CollisionSurface b(pair.mesh_b.triangles, pair.mesh_b.num_nodes(), false);
  const double thickness = 0.01 * static_cast<double>(state.range(1)) * pair.cell;
  ProximityQuery query;
  ProximityResult result;
  int step = 0;
  pair.Deform(step, a.positions(), b.positions());
  a.Update(1.5, false);
  b.Update(1.5, false);
  double contacts = 0, pairs = 0, node_pairs = 0;
  for (auto _ : state) {
    state.PauseTiming();
    pair.Deform(++step, a.positions(), b.positions());
    state.ResumeTiming();
    a.Update(1.5, false);
    b.Update(1.5, false);
    query.Query(a, b, thickness, true, result);
    contacts += static_cast<double>(result.size());
    pairs += static_cast<double>(query.last_triangle_pairs());
    node_pairs += static_cast<double>(query.last_node_pairs());
    benchmark::DoNotOptimize(result.a_on_b.data());
  }
  state.counters["tri_pairs"] = pairs / static_cast<double>(state.iterations());
  state.counters["node_pairs"] = node_pairs / static_cast<double>(state.iterations());
  state.counters["triangles_each"] = static_cast<double>(a.num_triangles());
  state.counters["contacts"] = contacts / static_cast<double>(state.iterations());
  state.counters["rebuilds"] = a.tree().num_builds() + b.tree().num_builds() - 2;
}
// {cells per side, thickness in % of a cell}.
BENCHMARK(BM_GipsiSheets)
    ->Args({100, 10})
    ->Args({100, 50})
    ->Args({224, 10})
    ->Args({224, 50})
    ->Unit(benchmark::kMillisecond);

// Refit only (both sheets), to split the cost.
void BM_GipsiRefit(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  SheetPair pair(n);
  CollisionSurface a(pair.mesh_a.triangles, pair.mesh_a.num_nodes(), false);
  CollisionSurface b(pair.mesh_b.triangles, pair.mesh_b.num_nodes(), false);
  int step = 0;
  pair.Deform(step, a.positions(), b.positions());
  a.Update(1.5, false);
  b.Update(1.5, false);
  for (auto _ : state) {
    state.PauseTiming();
    pair.Deform(++step, a.positions(), b.positions());
    state.ResumeTiming();
    a.Update(1.5, false);
    b.Update(1.5, false);
  }
}
BENCHMARK(BM_GipsiRefit)->Arg(100)->Arg(224)->Unit(benchmark::kMillisecond);

// One 20k sheet folded over itself (gap 0.6 cell, thickness 1 cell), wobbling.
void BM_GipsiSelf(benchmark::State& state) {
  const int n = 100;
  Mesh mesh = MakeTriangleSheet(Vec3::Zero(), Vec3(2, 0, 0), Vec3(0, 1, 0), {2 * n, n / 2});
  CollisionSurface s(mesh.triangles, mesh.num_nodes(), false);
  const double cell = 1.0 / n, gap = 0.6 * cell, r = gap / 2;
  auto fold = [&](int step) {
    Points& x = s.positions();
    for (Index v = 0; v < x.cols(); ++v) {
      const double u = mesh.nodes(0, v), y = mesh.nodes(1, v);
      const double wobble = 0.2 * cell * std::sin(8 * y + 0.05 * step);
      const double arc = std::numbers::pi * r;
      if (u <= 1) {
        x.col(v) << u, y, wobble * u;
      } else if (u <= 1 + arc) {
        const double th = (u - 1) / r;
        x.col(v) << 1 + r * std::sin(th), y, r - r * std::cos(th) + wobble;
      } else {
        const double back = 1 - (u - 1 - arc);
        x.col(v) << back, y, gap + wobble * back;
      }
    }
  };
  int step = 0;
  fold(step);
  s.Update(1.5, true);
  ProximityQuery query;
  ProximityResult result;
  double contacts = 0;
  for (auto _ : state) {
    state.PauseTiming();
    fold(++step);
    state.ResumeTiming();
    s.Update(1.5, true);
    query.QuerySelf(s, cell, true, result);
    contacts += static_cast<double>(result.size());
  }
  state.counters["triangles"] = static_cast<double>(s.num_triangles());
  state.counters["contacts"] = contacts / static_cast<double>(state.iterations());
}
BENCHMARK(BM_GipsiSelf)->Unit(benchmark::kMillisecond);

#ifdef GIPSI_HAVE_FCL
std::vector<fcl::Vector3d> FclPoints(const Points& x) {
  std::vector<fcl::Vector3d> out(static_cast<std::size_t>(x.cols()));
  for (Index v = 0; v < x.cols(); ++v) out[static_cast<std::size_t>(v)] = x.col(v);
  return out;
}

std::shared_ptr<fcl::BVHModel<fcl::AABBd>> FclModel(const Mesh& mesh, const Points& x) {
  auto model = std::make_shared<fcl::BVHModel<fcl::AABBd>>();
  std::vector<fcl::Triangle> tris;
  for (Index t = 0; t < mesh.triangles.cols(); ++t)
    tris.emplace_back(mesh.triangles(0, t), mesh.triangles(1, t), mesh.triangles(2, t));
  model->beginModel();
  model->addSubModel(FclPoints(x), tris);
  model->endModel();
  return model;
}

void BM_FclSheets(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const bool collide = state.range(1) != 0;
  SheetPair pair(n);
  Points xa(3, pair.mesh_a.num_nodes()), xb(3, pair.mesh_b.num_nodes());
  int step = 0;
  pair.Deform(step, xa, xb);
  auto ma = FclModel(pair.mesh_a, xa);
  auto mb = FclModel(pair.mesh_b, xb);
  fcl::CollisionObjectd oa(ma), ob(mb);
  fcl::CollisionRequestd request(1 << 30, false);
  fcl::CollisionResultd result;
  double contacts = 0;
  for (auto _ : state) {
    state.PauseTiming();
    pair.Deform(++step, xa, xb);
    const auto pa = FclPoints(xa), pb = FclPoints(xb);
    state.ResumeTiming();
    ma->beginUpdateModel();
    ma->updateSubModel(pa);
    ma->endUpdateModel(true, true);
    mb->beginUpdateModel();
    mb->updateSubModel(pb);
    mb->endUpdateModel(true, true);
    oa.computeAABB();
    ob.computeAABB();
    if (collide) {
      result.clear();
      fcl::collide(&oa, &ob, request, result);
      contacts += static_cast<double>(result.numContacts());
    }
  }
  state.counters["contacts"] = contacts / static_cast<double>(state.iterations());
}
// {cells, collide?}: refit only, and refit + collide.
BENCHMARK(BM_FclSheets)
    ->Args({100, 0})
    ->Args({100, 1})
    ->Args({224, 0})
    ->Args({224, 1})
    ->Unit(benchmark::kMillisecond);
#endif

}  // namespace
}  // namespace gipsi
