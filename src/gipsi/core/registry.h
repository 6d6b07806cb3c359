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
#include <vector>

#include "gipsi/base/json_node.h"
#include "gipsi/core/connector.h"
#include "gipsi/core/material.h"
#include "gipsi/core/sim_object.h"
#include "gipsi/numerics/ode.h"

/// Version of the plugin interface; a plugin built against another version is refused.
/// 2: checkpoint hooks; 3: haptic local models by type; 4: SimObject's stop token, local models
/// in core; 5: cavities through the CavityWall capability, not a SimObject virtual; 6: snapshot
/// hooks (NewObjectState, CopyObjectState, SetObjectState) on SimObject and Connector; 7:
/// connector ports (Connector::UseField, …, RequireOrder; gipsi/core/port.h).
#define GIPSI_PLUGIN_ABI_VERSION 7

namespace gipsi {

class TypeRegistry;
class Coordinator;
class CellModel;
class LocalModelBuilder;

/// Looks up meshes declared in the scene by name (implemented by the scene loader).
class MeshProvider {
 public:
  virtual ~MeshProvider() = default;
  /// The mesh called `name`; throws InputError at `where` if there is none.
  [[nodiscard]] virtual std::shared_ptr<const Mesh> GetMesh(std::string_view name,
                                                            const JsonNode& where) const = 0;
};

/// An object built from scene JSON with its time step (for aggregates that build their parts).
struct BuiltObject {
  std::unique_ptr<SimObject> object;
  double dt = 0;
};
/// Builds a complete object (factory, time step, boundary conditions, display) from its JSON.
using BuildObjectFn = std::function<BuiltObject(const std::string& name, const JsonNode& params)>;

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
  /// The domain mesh named by params.domain (required).
  [[nodiscard]] std::shared_ptr<const Mesh> DomainMesh() const;
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
using IntegratorFactory = std::function<std::unique_ptr<ExplicitIntegrator>()>;
/// Builds a material from its JSON object (the "law" key is already consumed).
using MaterialFactory = std::function<std::shared_ptr<const Material>(const JsonNode&)>;
/// Builds a cardiac cell model from its JSON object ({"model": name, ...parameters}; see
/// gipsi/models/ep/cell_models.h); throws InputError naming the JSON path of a bad parameter.
using CellModelFactory = std::function<std::shared_ptr<const CellModel>(const JsonNode& params)>;
/// Builds the haptic local-model builder (gipsi/core/local_model.h) of an object of
/// the type it is registered under; `rings` is the HapticCoupling's neighbourhood size (0-5),
/// for builders that use one. May throw InputError (e.g. an object without a boundary).
using LocalModelFactory =
    std::function<std::unique_ptr<LocalModelBuilder>(SimObject& object, int rings)>;

/// Factories by type name, for one kind of product. Not copyable; movable.
template <class Factory>
class FactoryTable {
 public:
  explicit FactoryTable(std::string kind) : kind_(std::move(kind)) {}
  /// Registers `factory` under `name`; aborts (programmer error) on a duplicate name.
  void Register(const std::string& name, Factory factory, std::string description);
  [[nodiscard]] bool Contains(std::string_view name) const { return table_.count(name) > 0; }
  /// The factory for `name`; throws InputError at `where` listing the known names.
  [[nodiscard]] const Factory& Get(std::string_view name, const JsonNode& where) const;
  /// (name, description) of every registered type, sorted by name.
  [[nodiscard]] std::vector<std::pair<std::string, std::string>> List() const;

 private:
  struct Entry {
    Factory factory;
    std::string description;
  };
  std::string kind_;
  std::map<std::string, Entry, std::less<>> table_;
};

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
  FactoryTable<CellModelFactory> cell_models{"cell model"};
  /// Haptic local models, keyed by the object type (SimObject::type_name()) they describe: a
  /// HapticCoupling can render any object whose type has one (plugins register their own).
  FactoryTable<LocalModelFactory> local_models{"haptic local model"};

  /// Builds the object described by `params` (its "type" picks the factory).
  [[nodiscard]] std::unique_ptr<SimObject> CreateObject(const std::string& name,
                                                        const JsonNode& params,
                                                        const MeshProvider& meshes,
                                                        const BuildObjectFn& build_object) const;
  /// Builds the connector described by `params` within `scope`.
  [[nodiscard]] std::unique_ptr<Connector> CreateConnector(const std::string& name,
                                                           const JsonNode& params,
                                                           const Coordinator& scope) const;
  /// The integrator named by the string at `where`.
  [[nodiscard]] std::unique_ptr<ExplicitIntegrator> CreateIntegrator(const JsonNode& where) const;

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
  std::vector<std::string> plugins_;
};

/// Registers the explicit integrators ("ExplicitEuler", "SymplecticEuler", "RK4").
void RegisterIntegrators(TypeRegistry& registry);

}  // namespace gipsi
