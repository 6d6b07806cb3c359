#pragma once
/// @file
/// The type registry: simulation objects, connectors and integrators are created by type name
/// from scene files. A third party adds a type by registering a factory, from its own code or
/// from a plugin shared library loaded by path (see `LoadPlugin` and plugins/example/).

#include <functional>
#include <map>
#include <memory>
#include <string>
#include <string_view>
#include <typeindex>
#include <vector>

#include "gipsi/base/error.h"
#include "gipsi/base/export.h"
#include "gipsi/base/json_node.h"
#include "gipsi/base/version.h"
#include "gipsi/core/connector.h"
#include "gipsi/core/material.h"
#include "gipsi/core/sim_object.h"
#include "gipsi/geometry/mesh_block.h"
#include "gipsi/numerics/ode.h"

/// Version of the plugin interface (the C++ classes and hooks a plugin builds on).
/// 2: checkpoint hooks; 3: haptic local models by type; 4: SimObject's stop token, local models
/// in core; 5: cavities through the CavityWall capability, not a SimObject virtual; 6: snapshot
/// hooks (NewObjectState, CopyObjectState, SetObjectState) on SimObject and Connector; 7:
/// connector ports (Connector::UseField, …, RequireOrder; gipsi/core/port.h); 8: cell models
/// and local models in tables a layer above declares (TypeRegistry::Table; CellModels,
/// LocalModels); 9: OdeIntegrator (implicit integrators, Step returns bool); 10: SimObject's
/// state cache hooks (SaveStateCache, RestoreStateCache, DropStateCache); 11:
/// Connector::failure_detail, and the ABI version tied to the package version; 12: state value
/// types for connectors (Connector::BindState, BindNoState) and aggregates
/// (AggregateObject::BindAggregateState, replacing SaveAggregateState), the HapticEndpoint
/// capability; 13: SolidMaterial::ElementStressAndStiffnessBatch (a new virtual); 14: meshes in
/// blocks (MeshProvider::GetMeshBlock, ObjectBuildContext::standalone), the
/// PartitionedObject capability; 15: PartitionedObject's reductions where the nodes are owned
/// (SelectOwnedNodes, ReadOwnedNodes, CombineAcross); 16: coupling split objects part to part
/// (PartitionedObject's local_part, whole_nodes_of_part, whole_tets_of_part, num_owned_nodes,
/// ShareOwnedNodeValues), checkpoints between serial and split objects
/// (SimObject::RestoreAppliedConditions, EpTissue a RowState); 17: boundary conditions and
/// boundary-field probes on split objects without their whole domain (PartitionedObject's
/// SelectWholeBoundary, SelectOwnedBoundaryVertices); 18: cavities of a split solid without its
/// whole mesh (SolidDistribution's has_whole_mesh, SelectWholeFaces); 19: objects coupled part to
/// part made in blocks (ObjectBuildContext::in_blocks replaces standalone;
/// TypeRegistry::splits_in_blocks and connector_part_use; Connector::couples_parts, checked against
/// part-only ends); 20: coupling objects split differently (PartitionedObject's
/// InterpolateAtPoints, PartsInterpolation; TypeRegistry::PartUse::kAnyParts); 21: a split
/// object without its whole domain stores its part's boundary conditions only
/// (PartitionedObject::SelectConditionItems replaces SelectWholeBoundary), and events may name
/// objects made in blocks (InBlocksObjects takes no events); 22: nearest-item copies between
/// split objects (PartitionedObject::NearestAtPoints); 23: boundary couplings of split objects
/// (PartitionedObject::InterpolateOnBoundary, BoundaryInterpolation, process()).
#define GIPSI_PLUGIN_INTERFACE 23
/// What a plugin's gipsi_plugin_abi_version() returns and the loader requires: the package's
/// major and minor version with the plugin interface, MAJOR·10⁶ + MINOR·10³ + INTERFACE. A
/// plugin thus loads only into the release line it was built against (0.1.x, as the CMake
/// package's SameMinorVersion and the libraries' SOVERSION) with the same interface.
#define GIPSI_PLUGIN_ABI_VERSION \
  (GIPSI_VERSION_MAJOR * 1000000 + GIPSI_VERSION_MINOR * 1000 + GIPSI_PLUGIN_INTERFACE)

GIPSI_EXPORT_BEGIN
namespace gipsi {

class TypeRegistry;
class Coordinator;

/// Looks up meshes declared in the scene by name (implemented by the scene loader).
class MeshProvider {
 public:
  virtual ~MeshProvider() = default;
  /// The mesh called `name`; throws InputError at `where` if there is none.
  [[nodiscard]] virtual std::shared_ptr<const Mesh> GetMesh(std::string_view name,
                                                            const JsonNode& where) const = 0;
  /// Block `rank` of `size` of the mesh called `name` (geometry/mesh_block.h), for an object
  /// split over processes. The default slices GetMesh's mesh (BlockOfMesh); the scene loader
  /// makes a generated box's block without the whole box and does not keep a mesh it read only
  /// to slice. Throws InputError at `where` as GetMesh.
  [[nodiscard]] virtual MeshBlock GetMeshBlock(std::string_view name, const JsonNode& where,
                                               int rank, int size) const {
    return BlockOfMesh(*GetMesh(name, where), rank, size);
  }
};

/// An object built from scene JSON with its time step (for aggregates that build their parts).
struct BuiltObject {
  std::unique_ptr<SimObject> object;
  double dt = 0;
};
/// Builds a complete object (factory, time step, boundary conditions, display) from its JSON;
/// `in_blocks` as ObjectBuildContext::in_blocks (InBlocksObjects, gipsi/core/in_blocks.h).
using BuildObjectFn =
    std::function<BuiltObject(const std::string& name, const JsonNode& params, bool in_blocks)>;

/// Everything an object factory may use. The JSON keys every object accepts (type, dt, domain,
/// display, boundary_conditions, integrator) are handled by the scene loader; factories read
/// their own keys and call `CheckKeys` with them.
struct ObjectBuildContext {
  std::string name;              ///< the object's name
  JsonNode params;               ///< its JSON object
  const TypeRegistry& registry;  ///< for integrators and nested objects
  const MeshProvider& meshes;
  /// Builds nested objects the way the scene loader builds top-level ones (for aggregates).
  const BuildObjectFn& build_object;

  /// Keys common to every object, accepted by CheckKeys in addition to the factory's own.
  static const std::vector<std::string>& CommonKeys();
  /// Throws InputError for a key that is neither common nor in `own`.
  void CheckKeys(std::initializer_list<std::string_view> own) const;
  /// A distributed run may make this object in blocks, without its whole domain on any process
  /// (gipsi/core/partitioned_object.h): its type can be (TypeRegistry::splits_in_blocks), no
  /// event or other object names it, and every connector naming it either couples parts with
  /// objects also made in blocks from the same domain mesh or uses only its global fields and
  /// capabilities (TypeRegistry::connector_part_use). Besides those, only probes, outputs and
  /// the schedule's order read it. Set by the scene loader for top-level objects, and by an
  /// aggregate made in blocks for its parts, by the same rule (InBlocksObjects,
  /// gipsi/core/in_blocks.h); false in serial runs.
  bool in_blocks = false;

  /// The domain mesh named by params.domain (required).
  [[nodiscard]] std::shared_ptr<const Mesh> DomainMesh() const;
  /// Block `rank` of `size` of that mesh (MeshProvider::GetMeshBlock).
  [[nodiscard]] MeshBlock DomainMeshBlock(int rank, int size) const;
};

/// Everything a connector factory may use: its JSON and the objects in its scope (the scene, or
/// the parts of an aggregate).
struct ConnectorBuildContext {
  std::string name;
  JsonNode params;
  const TypeRegistry& registry;
  const Coordinator& scope;
  /// Throws InputError for a key that is neither common ("type", "every", "description") nor in
  /// `own`.
  void CheckKeys(std::initializer_list<std::string_view> own) const;
  /// The object named by the string at params[key]; throws InputError naming the path.
  [[nodiscard]] SimObject& Object(std::string_view key) const;
  /// Splits "object.field" found at params[key] into the object and its field id (the field
  /// may itself be dotted for aggregates: "heart.muscle.position" → object "heart.muscle").
  [[nodiscard]] std::pair<SimObject*, FieldId> ObjectField(std::string_view key) const;
};

using ObjectFactory = std::function<std::unique_ptr<SimObject>(const ObjectBuildContext&)>;
using ConnectorFactory = std::function<std::unique_ptr<Connector>(const ConnectorBuildContext&)>;
using IntegratorFactory = std::function<std::unique_ptr<OdeIntegrator>()>;
/// Builds a material from its JSON object (the "law" key is already consumed).
using MaterialFactory = std::function<std::shared_ptr<const Material>(const JsonNode&)>;
/// Factories by type name, for one kind of product. Not copyable; movable.
template <class Factory>
class FactoryTable {
 public:
  explicit FactoryTable(std::string kind) : kind_(std::move(kind)) {}
  /// Registers `factory` under `name`; aborts (programmer error) on a duplicate name.
  void Register(const std::string& name, Factory factory, std::string description) {
    GIPSI_CHECK(!name.empty() && factory, "empty {} registration", kind_);
    GIPSI_CHECK(!Contains(name), "{} '{}' registered twice", kind_, name);
    table_.emplace(name, Entry{std::move(factory), std::move(description)});
  }
  /// Replaces the factory registered under `name`, keeping its description unless one is given:
  /// a build that runs the type another way (a distributed run, gipsi/parallel/). Aborts
  /// (programmer error) if `name` is not registered.
  void Replace(const std::string& name, Factory factory, std::string description = {}) {
    auto it = table_.find(name);
    GIPSI_CHECK(it != table_.end() && factory, "{} '{}' replaced before it was registered", kind_,
                name);
    it->second.factory = std::move(factory);
    if (!description.empty()) it->second.description = std::move(description);
  }
  [[nodiscard]] bool Contains(std::string_view name) const { return table_.count(name) > 0; }
  /// The factory for `name`, or null.
  [[nodiscard]] const Factory* Find(std::string_view name) const {
    auto it = table_.find(name);
    return it == table_.end() ? nullptr : &it->second.factory;
  }
  /// The factory for `name`; throws InputError at `where` listing the known names.
  [[nodiscard]] const Factory& Get(std::string_view name, const JsonNode& where) const {
    auto it = table_.find(name);
    if (it == table_.end()) FailUnknown(kind_, name, Names(), where);
    return it->second.factory;
  }
  /// (name, description) of every registered type, sorted by name.
  [[nodiscard]] std::vector<std::pair<std::string, std::string>> List() const {
    std::vector<std::pair<std::string, std::string>> out;
    for (const auto& [n, e] : table_) out.emplace_back(n, e.description);
    return out;
  }
  /// The registered names, sorted.
  [[nodiscard]] std::vector<std::string> Names() const {
    std::vector<std::string> out;
    for (const auto& [n, e] : table_) out.push_back(n);
    return out;
  }

 private:
  struct Entry {
    Factory factory;
    std::string description;
  };
  std::string kind_;
  std::map<std::string, Entry, std::less<>> table_;
};

/// Throws InputError at `where`: "unknown KIND 'NAME' (did you mean …); known: …".
[[noreturn]] void FailUnknown(std::string_view kind, std::string_view name,
                              const std::vector<std::string>& known, const JsonNode& where);

/// All factories. Create one, call `RegisterBuiltins`, optionally `LoadPlugin`, and pass it to
/// the scene loader. Plugins stay loaded for the registry's lifetime and beyond (never unloaded,
/// so objects they created stay valid). Not copyable or movable.
class TypeRegistry {
 public:
  TypeRegistry() = default;
  TypeRegistry(const TypeRegistry&) = delete;
  TypeRegistry& operator=(const TypeRegistry&) = delete;

  FactoryTable<ObjectFactory> objects{"object type"};
  FactoryTable<ConnectorFactory> connectors{"connector type"};
  FactoryTable<IntegratorFactory> integrators{"integrator"};
  FactoryTable<MaterialFactory> materials{"material law"};

  /// Set by a distributed run (gipsi/parallel/): the scene loader then builds the domain mesh
  /// of objects made in blocks (ObjectBuildContext::in_blocks) that nothing else uses only when
  /// its factory asks for it, whole or in blocks (MeshProvider::GetMeshBlock), and keeps no
  /// whole mesh it made only to cut blocks from. False: every mesh is built whole first.
  bool meshes_in_blocks = false;
  /// Object types a distributed run can make in blocks, and when from the object's JSON (e.g. a
  /// Monodomain without boundary conditions): set by the run's own types (gipsi/parallel/).
  /// Empty in serial runs, where nothing is made in blocks.
  std::map<std::string, std::function<bool(const JsonNode& params)>, std::less<>> splits_in_blocks;
  /// How a connector uses objects made in blocks (of which each process holds only its part).
  enum class PartUse {
    kWhole,       ///< it needs its objects whole (every type not in connector_part_use)
    kPartToPart,  ///< it couples the parts of objects split alike, made in blocks from one
                  ///< domain mesh (Connector::couples_parts), or of objects all whole
    kGlobal,      ///< it uses only its objects' global fields and capabilities: any of them may
                  ///< be made in blocks
    kAnyParts,    ///< it couples the parts of objects split any way (other meshes, other cuts)
                  ///< or whole (a barycentric or nearest FieldCopy): any of them may be made in
                  ///< blocks
  };
  /// Connector types that can join objects made in blocks, and how, from the connector's JSON
  /// (e.g. a FieldCopy couples any parts with a "barycentric" or "nearest" mapping, and parts
  /// split alike with another): registered with the
  /// connector. The scene loader makes objects in blocks only where every connector naming them
  /// allows it (ObjectBuildContext::in_blocks).
  std::map<std::string, std::function<PartUse(const JsonNode& params)>, std::less<>>
      connector_part_use;

  /// The table of another kind of product, which the layer that defines the product declares
  /// (the kernel names no model concept): e.g. `CellModels(registry)` in
  /// gipsi/models/ep/cell_models.h is `registry.Table<CellModelFactory>("cell model")`. The
  /// table is created empty on first use; a kind is always used with the same factory type
  /// (checked). Not thread-safe: register and look up while the scene is built.
  template <class Factory>
  [[nodiscard]] FactoryTable<Factory>& Table(const std::string& kind) {
    return FindTable<Factory>(kind);
  }
  template <class Factory>
  [[nodiscard]] const FactoryTable<Factory>& Table(const std::string& kind) const {
    return FindTable<Factory>(kind);
  }
  /// The kinds of the tables created by Table, sorted.
  [[nodiscard]] std::vector<std::string> TableKinds() const;
  /// (name, description) of every product in the table of `kind` (one of TableKinds()).
  [[nodiscard]] std::vector<std::pair<std::string, std::string>> ListTable(
      std::string_view kind) const;

  /// Builds the object described by `params` (its "type" picks the factory);
  /// `in_blocks` as ObjectBuildContext::in_blocks.
  [[nodiscard]] std::unique_ptr<SimObject> CreateObject(const std::string& name,
                                                        const JsonNode& params,
                                                        const MeshProvider& meshes,
                                                        const BuildObjectFn& build_object,
                                                        bool in_blocks = false) const;
  /// Builds the connector described by `params` within `scope`.
  [[nodiscard]] std::unique_ptr<Connector> CreateConnector(const std::string& name,
                                                           const JsonNode& params,
                                                           const Coordinator& scope) const;
  /// The integrator named by the string at `where`.
  [[nodiscard]] std::unique_ptr<OdeIntegrator> CreateIntegrator(const JsonNode& where) const;

  /// The material described by `node` ({"law": name, ...parameters}); throws InputError at the
  /// node unless the law exists and belongs to `family`.
  [[nodiscard]] std::shared_ptr<const Material> CreateMaterial(const JsonNode& node,
                                                               std::string_view family) const;
  /// CreateMaterial, cast to the family's base class `M`.
  template <class M>
  [[nodiscard]] std::shared_ptr<const M> CreateMaterialAs(const JsonNode& node,
                                                          std::string_view family) const {
    return std::static_pointer_cast<const M>(CreateMaterial(node, family));
  }

  /// Loads a plugin shared library: it must export
  /// `extern "C" int gipsi_plugin_abi_version()` (returning GIPSI_PLUGIN_ABI_VERSION) and
  /// `extern "C" void gipsi_register_plugin(gipsi::TypeRegistry&)`. Throws InputError if the
  /// file cannot be loaded, lacks the symbols or was built for another ABI version. Loading the
  /// same path twice is a no-op.
  void LoadPlugin(const std::string& path);
  [[nodiscard]] const std::vector<std::string>& loaded_plugins() const { return plugins_; }

 private:
  struct AnyTable {
    std::type_index type;
    std::shared_ptr<void> table;
    std::function<std::vector<std::pair<std::string, std::string>>()> list;
  };
  template <class Factory>
  FactoryTable<Factory>& FindTable(const std::string& kind) const {
    auto it = tables_.find(kind);
    if (it == tables_.end()) {
      auto table = std::make_shared<FactoryTable<Factory>>(kind);
      auto list = [t = table.get()] { return t->List(); };
      it = tables_.emplace(kind, AnyTable{typeid(Factory), table, list}).first;
    }
    GIPSI_CHECK(it->second.type == std::type_index(typeid(Factory)),
                "the {} table is used with two factory types", kind);
    return *static_cast<FactoryTable<Factory>*>(it->second.table.get());
  }

  std::vector<std::string> plugins_;
  mutable std::map<std::string, AnyTable, std::less<>> tables_;
};

/// Registers the explicit integrators ("ExplicitEuler", "SymplecticEuler", "RK4").
void RegisterIntegrators(TypeRegistry& registry);

}  // namespace gipsi
GIPSI_EXPORT_END
