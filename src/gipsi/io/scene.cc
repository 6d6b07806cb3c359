#include "gipsi/io/scene.h"

#include <algorithm>
#include <cctype>
#include <cstdlib>
#include <fstream>
#include <functional>
#include <optional>
#include <set>
#include <sstream>

#include <fmt/format.h>

#include "gipsi/base/error.h"
#include "gipsi/base/file_io.h"
#include "gipsi/base/log.h"
#include "gipsi/base/units.h"
#include "gipsi/core/in_blocks.h"
#include "gipsi/geometry/generators.h"
#include "gipsi/io/gmsh_block_reader.h"
#include "gipsi/io/mesh_io.h"
#include "gipsi/io/tetgen_reader.h"
#include "gipsi/io/vtk_legacy_reader.h"
#include "gipsi/io/vtu_block_reader.h"

namespace gipsi {
namespace {

/// The keys of a "meshes" entry, and the ones that exclude each other.
void CheckMeshEntry(const JsonNode& node) {
  node.CheckKeys({"file",         "generate", "scale",         "translate", "min",
                  "max",          "cells",    "origin",        "u",         "v",
                  "endo",         "epi",      "base_z",        "size",      "inner_radius",
                  "outer_radius", "height",   "tets_per_cell", "surface",   "description",
                  "nodes",        "tets",     "triangles",     "order"});
  if (int(node.Has("file")) + int(node.Has("generate")) + int(node.Has("nodes")) != 1)
    node.Fail("expected exactly one of 'file', 'generate', 'nodes'");
  if (auto order = node.Find("order")) {
    const auto gen = node.Find("generate");
    const std::string kind = gen && gen->is_string() ? gen->AsString() : "";
    if (kind != "ellipsoid_shell" && kind != "cylinder_shell")
      order->Fail(
          "only the generators \"ellipsoid_shell\" and \"cylinder_shell\" take 'order' (a "
          "Gmsh file's elements have their own)");
  }
  if (!node.Has("nodes"))
    for (const char* key : {"tets", "triangles"})
      if (node.Has(key)) node.At(key).Fail("only a mesh given by its 'nodes' takes this key");
}

std::array<int, 3> Cells3(const JsonNode& node) {
  auto v = node.AsInts();
  if (v.size() != 3) node.Expected("an array of 3 positive integers");
  std::array<int, 3> out{};
  for (int i = 0; i < 3; ++i) {
    if (v[static_cast<std::size_t>(i)] < 1 || v[static_cast<std::size_t>(i)] > 1000)
      node.Expected("an array of 3 integers in [1, 1000]");
    out[static_cast<std::size_t>(i)] = static_cast<int>(v[static_cast<std::size_t>(i)]);
  }
  return out;
}

/// The scene's meshes. Each is built whole when the "meshes" section is read, except when the
/// registry asks for meshes in blocks (a distributed run): then each is built when an object
/// first asks for it, whole (GetMesh) or as one process's block (GetMeshBlock, for an object made
/// in blocks), and a block is made without keeping the whole mesh; a mesh no object asks for is
/// built whole at the end (BuildTheRest), so a mistake in it is still reported.
class SceneMeshes final : public MeshProvider {
 public:
  using StageFn = std::function<void(const std::string& name, const JsonNode& node)>;
  SceneMeshes(std::map<std::string, std::shared_ptr<const Mesh>>& meshes,
              std::filesystem::path base_dir, const SceneLimits& limits, StageFn stage)
      : meshes_(meshes),
        base_dir_(std::move(base_dir)),
        limits_(limits),
        stage_(std::move(stage)) {}

  /// Builds the mesh `name` now.
  void Build(const std::string& name, const JsonNode& node) const {
    stage_(name, node);
    auto mesh = std::make_shared<const Mesh>(BuildMesh(node, base_dir_));
    CheckSize(node, mesh->num_nodes(), mesh->num_tets() + mesh->num_triangles());
    meshes_[name] = std::move(mesh);
  }
  /// Leaves the mesh `name` to be built when it is asked for.
  void Defer(const std::string& name, const JsonNode& node) { deferred_.emplace(name, node); }
  /// Builds the deferred meshes nobody asked for (so a mistake in them is still reported).
  void BuildTheRest() {
    for (const auto& [name, node] : deferred_)
      if (!meshes_.count(name) && !in_blocks_.count(name)) Build(name, node);
  }

  std::shared_ptr<const Mesh> GetMesh(std::string_view name, const JsonNode& where) const override {
    auto it = meshes_.find(std::string(name));
    if (it != meshes_.end()) return it->second;
    if (auto d = deferred_.find(std::string(name)); d != deferred_.end()) {
      Build(d->first, d->second);
      return meshes_.at(d->first);
    }
    FailUnknown(name, where);
  }

  MeshBlock GetMeshBlock(std::string_view name, const JsonNode& where, int rank,
                         int size) const override {
    auto d = deferred_.find(std::string(name));
    if (d == deferred_.end() || meshes_.count(d->first))
      return MeshProvider::GetMeshBlock(name, where, rank, size);
    const JsonNode& node = d->second;
    if (!in_blocks_.count(d->first)) stage_(d->first, node);
    in_blocks_.insert(d->first);
    std::optional<MeshBlock> block;
    const auto generate = node.Find("generate");
    const auto file = node.Find("file");
    if (generate && generate->is_string() && generate->AsString() == "box") {
      block = BoxBlock(node, rank, size);
    } else if (file && file->is_string() &&
               (IsGmshFile(file->AsString()) || IsTetGenFile(file->AsString()) ||
                LowerExtension(file->AsString()) == ".vtk" ||
                LowerExtension(file->AsString()) == ".vtu")) {
      CheckMeshEntry(node);
      const std::string& name = file->AsString();
      std::filesystem::path path = name;
      if (path.is_relative()) path = base_dir_ / path;
      try {
        block = IsGmshFile(name)                 ? ReadGmshBlock(path, rank, size)
                : IsTetGenFile(name)             ? ReadTetGenBlock(path, rank, size)
                : LowerExtension(name) == ".vtk" ? ReadVtkLegacyBlock(path, rank, size)
                                                 : ReadVtuBlock(path, rank, size);
        if (block && block->num_nodes == 0)  // as ReadMesh refuses it
          ThrowInputError(path.string(), "",
                          fmt::format("the file holds no nodes: an empty mesh, or not a {} file",
                                      path.extension().string()));
      } catch (const InputError& e) {
        file->Fail(e.what());
      }
      if (block)
        Transform(node, *block);
      else if (rank == 0)
        Log().info(
            "{}: {}: every process reads this file whole to cut its block (Gmsh files with "
            "linear elements in one node section, and VTK unstructured grids with linear cells "
            "in one piece, are read in blocks)",
            node.file(), file->path());
    }
    if (!block) {  // read whole, sliced, not kept
      const Mesh whole = BuildMesh(node, base_dir_);
      CheckSize(node, whole.num_nodes(), whole.num_tets() + whole.num_triangles());
      block = BlockOfMesh(whole, rank, size);
    }
    CheckSize(node, block->num_nodes, block->num_tets + block->num_triangles);
    return std::move(*block);
  }

 private:
  [[noreturn]] void FailUnknown(std::string_view name, const JsonNode& where) const {
    std::vector<std::string> names;
    for (const auto& [n, m] : meshes_) names.push_back(n);
    for (const auto& [n, m] : deferred_)
      if (!meshes_.count(n)) names.push_back(n);
    std::sort(names.begin(), names.end());
    where.Fail(fmt::format("no mesh named '{}'{} in 'meshes'", name, SuggestClosest(name, names)));
  }

  // A generated box's block, made without the whole box (BuildMesh's box, then its transform).
  MeshBlock BoxBlock(const JsonNode& node, int rank, int size) const {
    CheckMeshEntry(node);
    HexSplit split = HexSplit::kSix;
    if (auto per_cell = node.Find("tets_per_cell")) {
      const std::int64_t n = per_cell->AsInt();
      if (n != 5 && n != 6) per_cell->Expected("5 or 6");
      split = n == 5 ? HexSplit::kFive : HexSplit::kSix;
    }
    MeshBlock block;
    try {
      block = MakeTetBoxBlock(node.Vector3("min"), node.Vector3("max"), Cells3(node.At("cells")),
                              split, rank, size);
    } catch (const InputError& e) {
      std::string what = e.what();
      if (what.rfind(node.file(), 0) == 0) throw;  // already located
      node.Fail(what);
    }
    Transform(node, block);
    return block;
  }

  // The entry's "scale" and "translate", as BuildMesh applies them.
  static void Transform(const JsonNode& node, MeshBlock& block) {
    const auto scale = node.Find("scale");
    const auto translate = node.Find("translate");
    if (scale || translate)
      block.nodes = ((scale ? scale->AsPositive() : 1.0) * block.nodes).colwise() +
                    (translate ? translate->AsVec3() : Vec3::Zero());
  }

  static std::string LowerExtension(const std::string& name) {
    std::string extension = std::filesystem::path(name).extension().string();
    std::transform(extension.begin(), extension.end(), extension.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    return extension;
  }
  static bool IsGmshFile(const std::string& name) { return LowerExtension(name) == ".msh"; }
  // ReadMesh reads these as TetGen files (io/mesh_io.cc).
  static bool IsTetGenFile(const std::string& name) {
    const std::string extension = LowerExtension(name);
    return extension == ".node" || extension == ".ele" || extension == ".face";
  }

  void CheckSize(const JsonNode& node, std::int64_t nodes, std::int64_t cells) const {
    if (std::max(nodes, cells) > limits_.max_mesh_cells)
      node.Fail(
          fmt::format("the mesh has {} nodes and {} cells, over the limit of {} (raise it with "
                      "`gipsi run --max-mesh-cells` if the scene is trusted)",
                      nodes, cells, limits_.max_mesh_cells));
  }

  std::map<std::string, std::shared_ptr<const Mesh>>& meshes_;
  std::filesystem::path base_dir_;
  const SceneLimits& limits_;
  StageFn stage_;
  std::map<std::string, JsonNode> deferred_;
  mutable std::set<std::string> in_blocks_;
};

/// Builds objects with the keys every object shares (dt, boundary_conditions, display).
class ObjectBuilder {
 public:
  ObjectBuilder(const TypeRegistry& registry, const SceneMeshes& meshes, Scene& scene,
                double default_dt)
      : registry_(registry), meshes_(meshes), scene_(scene), default_dt_(default_dt) {
    fn_ = [this](const std::string& name, const JsonNode& node, bool in_blocks) {
      return Build(name, node, in_blocks);
    };
  }

  /// `in_blocks` as ObjectBuildContext::in_blocks.
  BuiltObject Build(const std::string& name, const JsonNode& node, bool in_blocks) {
    if (name.empty() || name.find_first_of("./ ") != std::string::npos)
      node.Fail(fmt::format("object name '{}' must be non-empty without '.', '/' or spaces", name));
    auto object = registry_.CreateObject(name, node, meshes_, fn_, in_blocks);
    double dt = default_dt_;
    if (auto d = node.Find("dt")) dt = ReadPositiveQuantity(*d, "s");
    if (!(dt > 0)) node.Fail("missing required key 'dt' (and schedule.dt is not set)");
    if (auto display = node.Find("display")) ApplyDisplay(*object, *display);
    if (auto bcs = node.Find("boundary_conditions")) {
      auto items = bcs->Items();
      for (std::size_t i = 0; i < items.size(); ++i) {
        BoundaryConditionSpec spec = ParseBoundaryCondition(items[i], *object, i);
        spec.Apply(object->boundary_conditions());
        std::string key = name + "/" + spec.name;
        if (!scene_.boundary_conditions.emplace(key, spec).second)
          items[i].At("name").Fail(fmt::format("duplicate condition name '{}'", spec.name));
      }
    }
    object->UpdateDisplay();
    return {std::move(object), dt};
  }

  const BuildObjectFn& fn() const { return fn_; }

 private:
  void ApplyDisplay(SimObject& object, const JsonNode& node) {
    DrawSpec draw = ParseDrawSpec(node, {"mesh", "mapping", "max_distance"});
    if (node.Has("mesh")) {
      auto mesh = meshes_.GetMesh(node.At("mesh").AsString(), node.At("mesh"));
      if (mesh->num_triangles() == 0)
        node.At("mesh").Fail("a display mesh needs triangles (a surface)");
      if (auto mapping = node.Find("mapping")) (void)mapping->AsChoice({"barycentric"});
      const Points& nodes = object.domain().nodes;
      const double diag = (nodes.rowwise().maxCoeff() - nodes.rowwise().minCoeff()).norm();
      try {
        object.EmbedDisplay(mesh->nodes, mesh->triangles,
                            node.NonNegative("max_distance", 0.05 * diag));
      } catch (const InputError& e) {
        node.Fail(e.what());
      }
    } else {
      for (const char* key : {"mapping", "max_distance"})
        if (node.Has(key)) node.At(key).Fail("only applies with a display 'mesh'");
    }
    if (node.Has("color") || node.Has("as") || node.Has("wireframe") || node.Has("visible") ||
        node.Has("size")) {
      try {  // resolve the field and geometry now, so errors name this JSON path
        (void)CheckDrawSpec(object, draw, object.name());
      } catch (const InputError& e) {
        // "object 'x': display: ..." is about the geometry, anything else about the colour.
        const bool geometry =
            std::string_view(e.what()).find("': display: ") != std::string_view::npos;
        if (!geometry && node.Has("color")) node.At("color").Fail(e.what());
        if (geometry && node.Has("as")) node.At("as").Fail(e.what());
        node.Fail(e.what());
      }
      scene_.display.emplace_back(&object, std::move(draw));
    }
  }

  const TypeRegistry& registry_;
  const SceneMeshes& meshes_;
  Scene& scene_;
  double default_dt_;
  BuildObjectFn fn_;
};

/// An output's sampling interval `every` [s] read from `node` (0: every macro step). Outputs are
/// sampled between macro steps, so an interval shorter than the macro step samples every macro
/// step: it is clamped to 0 with a warning naming the macro step (an interval of 1e-15 s once
/// meant 1e15 loop turns per simulated second: a hang).
double ClampSamplingInterval(const JsonNode& node, double every, const Kernel& kernel) {
  if (every > 0 && every < kernel.macro_dt() * (1 - 1e-9)) {
    Log().warn(
        "{}: {}: a sampling interval of {:.6g} s is shorter than the macro step of {:.6g} s "
        "(schedule.dt, or the largest object dt): sampling every macro step instead",
        node.file(), node.path(), every, kernel.macro_dt());
    return 0;
  }
  return every;
}

/// "on_failure": "stop" or {"retry": {"max_halvings": N}} (1 <= N <= 20).
FailurePolicy ParseFailurePolicy(const JsonNode& node) {
  FailurePolicy policy;
  if (node.is_string()) {
    (void)node.AsChoice({"stop"});
    return policy;
  }
  if (!node.is_object()) node.Expected("\"stop\" or {\"retry\": {\"max_halvings\": N}}");
  node.CheckKeys({"retry"});
  const JsonNode retry = node.At("retry");
  retry.CheckKeys({"max_halvings"});
  const std::int64_t halvings = retry.Int("max_halvings");
  if (halvings < 1 || halvings > 20) retry.At("max_halvings").Expected("an integer from 1 to 20");
  policy.max_halvings = static_cast<int>(halvings);
  return policy;
}

void ParseEvent(const JsonNode& node, Scene& scene) {
  node.CheckKeys({"at", "object", "apply", "remove", "set_field", "description"});
  const double at = ReadPositiveQuantity(node.At("at"), "s", /*allow_zero=*/true);
  // The kernel fires an event at the first macro step starting at or after it: one at or after
  // the end would never fire.
  if (at >= scene.end_time - 1e-9 * scene.kernel->macro_dt())
    node.At("at").Fail(fmt::format(
        "the event at {:.6g} s would never fire: the run ends at schedule.end = {:.6g} s", at,
        scene.end_time));
  JsonNode object_node = node.At("object");
  std::string object_name = object_node.AsString();
  SimObject* object = nullptr;
  try {
    object = &scene.kernel->FindObject(object_name);
  } catch (const InputError& e) {
    object_node.Fail(e.what());
  }
  int actions = int(node.Has("apply")) + int(node.Has("remove")) + int(node.Has("set_field"));
  if (actions != 1) node.Fail("expected exactly one of 'apply', 'remove', 'set_field'");
  ScheduledEvent event;
  event.time = at;
  if (auto apply = node.Find("apply")) {
    BoundaryConditionSpec spec = ParseBoundaryCondition(*apply, *object, 1000);
    event.description =
        node.String("description",
                    fmt::format("apply boundary condition '{}' to '{}'", spec.name, object_name));
    event.action = [object, spec](Kernel&) { spec.Apply(object->boundary_conditions()); };
    scene.boundary_conditions.emplace(object_name + "/" + spec.name, spec);
  } else if (auto remove = node.Find("remove")) {
    std::string key = object_name + "/" + remove->AsString();
    auto it = scene.boundary_conditions.find(key);
    if (it == scene.boundary_conditions.end())
      remove->Fail(
          fmt::format("object '{}' has no boundary condition named '{}' (declared "
                      "before this event)",
                      object_name, remove->AsString()));
    BoundaryConditionSpec spec = it->second;
    event.description = node.String(
        "description",
        fmt::format("remove boundary condition '{}' from '{}'", spec.name, object_name));
    event.action = [object, spec](Kernel&) { spec.Remove(object->boundary_conditions()); };
  } else {
    JsonNode set = node.At("set_field");
    set.CheckKeys({"field", "value"});
    FieldId id;
    try {
      id = object->FindField(set.String("field"));
    } catch (const InputError& e) {
      set.At("field").Fail(e.what());
    }
    const FieldInfo& info = object->field_info(id);
    if (!info.writable()) set.At("field").Fail("the field is read-only");
    JsonNode value = set.At("value");
    Eigen::VectorXd v(info.components);
    if (info.components == 1 && value.is_number()) {
      v[0] = value.AsNumber();
    } else {
      auto numbers = value.AsNumbers();
      if (static_cast<int>(numbers.size()) != info.components)
        value.Expected(fmt::format("{} numbers", info.components));
      for (int c = 0; c < info.components; ++c) v[c] = numbers[static_cast<std::size_t>(c)];
    }
    Eigen::MatrixXd data = v.replicate(1, object->FieldCount(id));
    event.description =
        node.String("description", fmt::format("set field '{}' of '{}'", info.name, object_name));
    event.action = [object, id, data](Kernel&) { object->WriteField(id, data); };
  }
  scene.kernel->ScheduleEvent(std::move(event));
}

}  // namespace

std::string ResolvePlugin(const std::string& entry, const std::filesystem::path& base_dir) {
  namespace fs = std::filesystem;
  if (entry.find('/') != std::string::npos) {
    fs::path path = entry;
    return (path.is_relative() ? base_dir / path : path).string();
  }
  const std::string file = entry.ends_with(".so") ? entry : entry + ".so";
  std::vector<fs::path> dirs;
  if (const char* env = std::getenv("GIPSI_PLUGIN_PATH")) {
    std::stringstream list(env);
    for (std::string dir; std::getline(list, dir, ':');)
      if (!dir.empty()) dirs.emplace_back(dir);
  }
  std::error_code ec;
  fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (!ec) {
    dirs.push_back(exe.parent_path().parent_path() / "plugins");            // build tree
    dirs.push_back(exe.parent_path().parent_path() / "lib/gipsi/plugins");  // installed
  }
  for (const auto& dir : dirs)
    if (fs::exists(dir / file)) return (dir / file).string();
  return (base_dir / file).string();  // LoadPlugin reports it missing, with this path
}

namespace {

/// Connectivity given in the scene (`key`: an array of `k` node indices per cell) into `out`
/// (k by cells); every index checked against `num_nodes` at its JSON path.
template <class Conn>
void ReadConnectivity(const JsonNode& node, std::string_view key, Index num_nodes, Conn& out) {
  constexpr int k = Conn::RowsAtCompileTime;
  const auto list = node.Find(key);
  if (!list) return;
  if (!list->is_array()) list->Expected(fmt::format("an array of [{} node indices]", k));
  out.resize(k, static_cast<Index>(list->size()));
  for (std::size_t e = 0; e < list->size(); ++e) {
    const JsonNode cell = list->Item(e);
    if (!cell.is_array() || cell.size() != k) cell.Expected(fmt::format("{} node indices", k));
    for (int a = 0; a < k; ++a) {
      const JsonNode id = cell.Item(static_cast<std::size_t>(a));
      const std::int64_t i = id.AsInt();
      if (i < 0 || i >= num_nodes)
        id.Expected(fmt::format("a node index in [0, {}] (0-based)", num_nodes - 1));
      out(a, static_cast<Index>(e)) = static_cast<int>(i);
    }
  }
}

/// A mesh written in the scene: "nodes" ([x, y, z] each) with "tets" and/or "triangles".
Mesh InlineMesh(const JsonNode& node) {
  const JsonNode nodes = node.At("nodes");
  if (!nodes.is_array() || nodes.size() == 0)
    nodes.Expected("a non-empty array of [x, y, z] node coordinates");
  if (!node.Has("tets") && !node.Has("triangles"))
    node.Fail("a mesh given by its 'nodes' needs 'tets' or 'triangles' too");
  Mesh mesh;
  mesh.nodes.resize(3, static_cast<Index>(nodes.size()));
  for (std::size_t i = 0; i < nodes.size(); ++i)
    mesh.nodes.col(static_cast<Index>(i)) = nodes.Item(i).AsVec3();
  ReadConnectivity(node, "tets", mesh.num_nodes(), mesh.tets);
  ReadConnectivity(node, "triangles", mesh.num_nodes(), mesh.triangles);
  mesh.Validate(node.file() + ": " + node.path());
  return mesh;
}

/// A Gmsh shell generator's "order": 1 (linear tets, the default) or 2 (second order).
int GeneratedOrder(const JsonNode& node) {
  const auto order = node.Find("order");
  if (!order) return 1;
  const std::int64_t value = order->AsInt();
  if (value != 1 && value != 2) order->Expected("1 (linear tets) or 2 (second order)");
  return static_cast<int>(value);
}

}  // namespace

Mesh BuildMesh(const JsonNode& node, const std::filesystem::path& base_dir) {
  CheckMeshEntry(node);
  Mesh mesh;
  if (node.Has("nodes")) {
    mesh = InlineMesh(node);
  } else if (auto file = node.Find("file")) {
    std::filesystem::path path = file->AsString();
    if (path.is_relative()) path = base_dir / path;
    try {
      mesh = ReadMesh(path);
    } catch (const InputError& e) {
      file->Fail(e.what());
    }
  } else {
    JsonNode gen = node.At("generate");
    std::string kind =
        gen.AsChoice({"box", "sheet", "ellipsoid_shell", "cylinder_shell", "tetrahedralize"});
    try {
      if (kind == "box") {
        HexSplit split = HexSplit::kSix;
        if (auto per_cell = node.Find("tets_per_cell")) {
          const std::int64_t n = per_cell->AsInt();
          if (n != 5 && n != 6) per_cell->Expected("5 or 6");
          split = n == 5 ? HexSplit::kFive : HexSplit::kSix;
        }
        mesh =
            MakeTetBox(node.Vector3("min"), node.Vector3("max"), Cells3(node.At("cells")), split);
      } else if (kind == "sheet") {
        auto cells = node.At("cells").AsInts();
        if (cells.size() != 2 || cells[0] < 1 || cells[1] < 1 || cells[0] > 2000 || cells[1] > 2000)
          node.At("cells").Expected("an array of 2 integers in [1, 2000]");
        mesh = MakeTriangleSheet(node.Vector3("origin"), node.Vector3("u"), node.Vector3("v"),
                                 {static_cast<int>(cells[0]), static_cast<int>(cells[1])});
      } else if (kind == "ellipsoid_shell") {
        EllipsoidShellSpec spec;
        auto endo = node.At("endo").AsNumbers();
        auto epi = node.At("epi").AsNumbers();
        if (endo.size() != 2) node.At("endo").Expected("[short radius, long radius]");
        if (epi.size() != 2) node.At("epi").Expected("[short radius, long radius]");
        spec.endo_short = endo[0];
        spec.endo_long = endo[1];
        spec.epi_short = epi[0];
        spec.epi_long = epi[1];
        spec.base_z = node.Number("base_z", spec.base_z);
        spec.mesh_size = node.Positive("size", spec.mesh_size);
        spec.order = GeneratedOrder(node);
        mesh = MakeEllipsoidShell(spec);
      } else if (kind == "tetrahedralize") {
        const JsonNode surface_node = node.At("surface");
        std::filesystem::path path = surface_node.AsString();
        if (path.is_relative()) path = base_dir / path;
        Mesh surface;
        try {
          surface = ReadMesh(path);
        } catch (const InputError& e) {
          surface_node.Fail(e.what());
        }
        if (surface.num_triangles() == 0)
          surface_node.Fail(fmt::format("'{}' has no triangles to fill", path.string()));
        mesh = MakeTetsInSurface(surface.nodes, surface.triangles, node.Positive("size"));
      } else {
        mesh =
            MakeCylinderShell(node.Positive("inner_radius"), node.Positive("outer_radius"),
                              node.Positive("height"), node.Positive("size"), GeneratedOrder(node));
      }
    } catch (const InputError& e) {
      std::string what = e.what();
      if (what.rfind(node.file(), 0) == 0) throw;  // already located
      node.Fail(what);
    }
  }
  const auto scale = node.Find("scale");
  const auto translate = node.Find("translate");
  if (scale || translate)
    mesh.Transform(scale ? scale->AsPositive() : 1.0,
                   translate ? translate->AsVec3() : Vec3::Zero());
  return mesh;
}

Scene LoadScene(const std::filesystem::path& file, TypeRegistry& registry,
                const SceneLimits& limits, const BuildProgressFn& progress) {
  const std::string text = ReadRegularFile(file, kMaxSceneFileBytes, "scene file");
  return LoadSceneFromString(text, file.string(), file.parent_path(), registry, limits, progress);
}

Scene LoadSceneFromString(std::string_view text, const std::string& name,
                          const std::filesystem::path& base_dir, TypeRegistry& registry,
                          const SceneLimits& limits, const BuildProgressFn& progress) {
  JsonDocument doc = JsonDocument::Parse(text, name);
  JsonNode root = doc.root();
  if (!root.is_object()) root.Expected("a JSON object");
  // Build stages for `progress`: each mesh and object, then connectors, events and probes.
  int stages_done = 0;
  int stages = 3;
  for (const char* key : {"meshes", "objects"})
    if (auto members = root.Find(key); members && members->is_object())
      stages += static_cast<int>(members->size());
  auto stage = [&](const std::string& what) {
    if (progress) progress(what, stages_done, stages);
    ++stages_done;
  };
  root.CheckKeys({"gipsi", "description", "units", "plugins", "meshes", "objects", "connectors",
                  "schedule", "probes", "outputs"});
  if (auto version = root.Find("gipsi"); version && version->AsInt() != 1)
    version->Fail("this GiPSi reads scene format version 1");
  if (auto units = root.Find("units")) (void)units->AsChoice({"SI"});

  Scene scene;
  scene.file = name;
  scene.kernel = std::make_unique<Kernel>();
  scene.limits = limits;

  if (auto plugins = root.Find("plugins")) {
    for (const auto& item : plugins->Items()) {
      std::string path = ResolvePlugin(item.AsString(), base_dir);
      try {
        registry.LoadPlugin(path);
      } catch (const InputError& e) {
        item.Fail(e.what());
      }
    }
  }

  SceneMeshes mesh_provider(
      scene.meshes, base_dir, limits, [&stage](const std::string& mesh_name, const JsonNode& node) {
        stage(
            fmt::format("mesh '{}'{}", mesh_name,
                        node.is_object() && node.Has("generate") && node.At("generate").is_string()
                            ? " (generate " + node.At("generate").AsString() + ")"
                            : ""));
      });
  // In a distributed run, every mesh is built when an object first asks for it: whole, or only
  // the process's block (never then the whole mesh) for an object made in blocks.
  if (auto meshes = root.Find("meshes")) {
    for (const auto& [mesh_name, node] : meshes->Members()) {
      if (registry.meshes_in_blocks)
        mesh_provider.Defer(mesh_name, node);
      else
        mesh_provider.Build(mesh_name, node);
    }
  }

  JsonNode schedule = root.At("schedule");
  schedule.CheckKeys({"end", "dt", "order", "events", "on_failure"});
  scene.end_time = ReadPositiveQuantity(schedule.At("end"), "s");
  const double macro_dt = schedule.Has("dt") ? ReadPositiveQuantity(schedule.At("dt"), "s") : 0.0;

  ObjectBuilder builder(registry, mesh_provider, scene, macro_dt);
  JsonNode objects = root.At("objects");
  if (objects.size() == 0) objects.Expected("at least one object");
  const std::set<std::string> in_blocks =
      InBlocksObjects(objects, root.Find("connectors"), registry);
  for (const auto& [object_name, node] : objects.Members()) {
    stage(fmt::format("object '{}'{}", object_name,
                      node.is_object() && node.Has("type") && node.At("type").is_string()
                          ? " (" + node.At("type").AsString() + ")"
                          : ""));
    BuiltObject built = builder.Build(object_name, node, in_blocks.count(object_name) > 0);
    try {
      scene.kernel->coordinator().AddObject(std::move(built.object), built.dt);
    } catch (const InputError& e) {
      node.Fail(e.what());
    }
  }
  mesh_provider.BuildTheRest();
  stage("connectors");
  if (auto connectors = root.Find("connectors")) {
    for (const auto& [connector_name, node] : connectors->Members()) {
      auto connector = registry.CreateConnector(connector_name, node, scene.kernel->coordinator());
      int every = static_cast<int>(node.Int("every", 1));
      if (every < 1) node.At("every").Expected("an integer >= 1");
      try {
        scene.kernel->coordinator().AddConnector(std::move(connector), every);
      } catch (const InputError& e) {
        node.Fail(e.what());
      }
    }
  }
  if (auto order = schedule.Find("order")) {
    try {
      scene.kernel->coordinator().SetOrder(order->AsStrings(), order->path());
    } catch (const InputError& e) {
      order->Fail(e.what());
    }
  }
  try {
    scene.kernel->Initialize(macro_dt);
  } catch (const WiringError& e) {
    ThrowInputError(name, e.order_path().empty() ? "connectors." + e.connector() : e.order_path(),
                    e.what());
  } catch (const InputError& e) {
    ThrowInputError(name, "objects", e.what());
  }
  stage("events");
  if (auto events = schedule.Find("events"))
    for (const auto& event : events->Items()) ParseEvent(event, scene);
  if (auto on_failure = schedule.Find("on_failure"))
    scene.kernel->SetFailurePolicy(ParseFailurePolicy(*on_failure));

  stage("probes and outputs");
  if (auto probes = root.Find("probes"))
    for (const auto& [probe_name, node] : probes->Members()) {
      scene.probes.push_back(ParseProbe(probe_name, node, *scene.kernel));
      if (auto every = node.Find("every"))
        scene.probes.back().every =
            ClampSamplingInterval(*every, scene.probes.back().every, *scene.kernel);
    }

  scene.output_directory = std::filesystem::path("out") / std::filesystem::path(name).stem();
  if (auto outputs = root.Find("outputs")) {
    outputs->CheckKeys({"directory", "vtu", "plots"});
    if (auto plots = outputs->Find("plots"))
      for (const auto& plot : plots->Items())
        scene.plots.push_back(ParsePlotSpec(plot, scene.probes));
    if (auto dir = outputs->Find("directory")) {
      // A scene may come from anyone: it names a folder under the working directory, and only
      // the person running it (`gipsi run --out`) may send the outputs elsewhere.
      const std::filesystem::path path = dir->AsString();
      const bool climbs = std::any_of(
          path.begin(), path.end(), [](const std::filesystem::path& part) { return part == ".."; });
      if (path.empty() || path.has_root_path() || climbs)
        dir->Expected(
            "a relative folder without '..' (the outputs stay under the working directory; "
            "`gipsi run --out DIR` writes elsewhere)");
      scene.output_directory = path;
    }
    if (auto vtu = outputs->Find("vtu")) {
      if (vtu->raw().is_boolean()) {
        scene.vtu.enabled = vtu->AsBool();
      } else {
        vtu->CheckKeys({"every", "objects", "display"});
        scene.vtu.every =
            vtu->Has("every") ? ReadPositiveQuantity(vtu->At("every"), "s", true) : 0.0;
        if (auto every = vtu->Find("every"))
          scene.vtu.every = ClampSamplingInterval(*every, scene.vtu.every, *scene.kernel);
        scene.vtu.display = vtu->Bool("display", true);
        if (auto names = vtu->Find("objects")) {
          scene.vtu.objects = names->AsStrings();
          for (std::size_t i = 0; i < scene.vtu.objects.size(); ++i) {
            try {
              (void)scene.kernel->FindObject(scene.vtu.objects[i]);
            } catch (const InputError& e) {
              names->Item(i).Fail(e.what());
            }
          }
        }
      }
    }
  }
  return scene;
}

}  // namespace gipsi
