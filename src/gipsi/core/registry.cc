#include "gipsi/core/registry.h"

#include <dlfcn.h>

#include <algorithm>
#include <filesystem>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "gipsi/base/error.h"
#include "gipsi/core/coordinator.h"

namespace gipsi {

const std::vector<std::string>& ObjectBuildContext::CommonKeys() {
  static const std::vector<std::string> keys = {
      "type", "dt", "domain", "display", "boundary_conditions", "integrator", "description"};
  return keys;
}

void ObjectBuildContext::CheckKeys(std::initializer_list<std::string_view> own) const {
  std::vector<std::string> allowed = CommonKeys();
  allowed.insert(allowed.end(), own.begin(), own.end());
  params.CheckKeys(allowed);
}

std::shared_ptr<const Mesh> ObjectBuildContext::DomainMesh() const {
  JsonNode node = params.At("domain");
  return meshes.GetMesh(node.AsString(), node);
}

MeshBlock ObjectBuildContext::DomainMeshBlock(int rank, int size) const {
  JsonNode node = params.At("domain");
  return meshes.GetMeshBlock(node.AsString(), node, rank, size);
}

void ConnectorBuildContext::CheckKeys(std::initializer_list<std::string_view> own) const {
  std::vector<std::string> allowed = {"type", "every", "description"};
  allowed.insert(allowed.end(), own.begin(), own.end());
  params.CheckKeys(allowed);
}

SimObject& ConnectorBuildContext::Object(std::string_view key) const {
  JsonNode node = params.At(key);
  std::string name = node.AsString();
  if (SimObject* object = scope.FindObject(name)) return *object;
  auto names = scope.ObjectNames();
  node.Fail(fmt::format("no object named '{}'{}", name, SuggestClosest(name, names)));
}

std::pair<SimObject*, FieldId> ConnectorBuildContext::ObjectField(std::string_view key) const {
  JsonNode node = params.At(key);
  std::string spec = node.AsString();
  auto dot = spec.rfind('.');
  if (dot == std::string::npos || dot == 0 || dot + 1 == spec.size())
    node.Expected("\"object.field\"");
  std::string object_name = spec.substr(0, dot);
  SimObject* object = scope.FindObject(object_name);
  if (!object)
    node.Fail(fmt::format("no object named '{}'{}", object_name,
                          SuggestClosest(object_name, scope.ObjectNames())));
  try {
    return {object, object->FindField(spec.substr(dot + 1))};
  } catch (const InputError& e) {
    node.Fail(e.what());
  }
}

void FailUnknown(std::string_view kind, std::string_view name,
                 const std::vector<std::string>& known, const JsonNode& where) {
  std::string list;
  for (const std::string& n : known) list += (list.empty() ? "" : ", ") + n;
  if (list.empty()) list = "none";
  where.Fail(
      fmt::format("unknown {} '{}'{}; known: {}", kind, name, SuggestClosest(name, known), list));
}

std::vector<std::string> TypeRegistry::TableKinds() const {
  std::vector<std::string> out;
  for (const auto& [kind, table] : tables_) out.push_back(kind);
  return out;
}

std::vector<std::pair<std::string, std::string>> TypeRegistry::ListTable(
    std::string_view kind) const {
  auto it = tables_.find(kind);
  GIPSI_CHECK(it != tables_.end(), "no {} table", kind);
  return it->second.list();
}

std::unique_ptr<SimObject> TypeRegistry::CreateObject(const std::string& name,
                                                      const JsonNode& params,
                                                      const MeshProvider& meshes,
                                                      const BuildObjectFn& build_object,
                                                      bool in_blocks) const {
  JsonNode type = params.At("type");
  const ObjectFactory& factory = objects.Get(type.AsString(), type);
  ObjectBuildContext context{name, params, *this, meshes, build_object, in_blocks};
  auto object = factory(context);
  GIPSI_CHECK(object != nullptr, "factory for '{}' returned null", type.AsString());
  return object;
}

std::unique_ptr<Connector> TypeRegistry::CreateConnector(const std::string& name,
                                                         const JsonNode& params,
                                                         const Coordinator& scope) const {
  JsonNode type = params.At("type");
  const ConnectorFactory& factory = connectors.Get(type.AsString(), type);
  ConnectorBuildContext context{name, params, *this, scope};
  auto connector = factory(context);
  GIPSI_CHECK(connector != nullptr, "factory for '{}' returned null", type.AsString());
  return connector;
}

std::unique_ptr<OdeIntegrator> TypeRegistry::CreateIntegrator(const JsonNode& where) const {
  return integrators.Get(where.AsString(), where)();
}

std::shared_ptr<const Material> TypeRegistry::CreateMaterial(const JsonNode& node,
                                                             std::string_view family) const {
  JsonNode law = node.At("law");
  auto material = materials.Get(law.AsString(), law)(node);
  GIPSI_CHECK(material != nullptr, "factory for '{}' returned null", law.AsString());
  if (material->family() != family)
    law.Fail(fmt::format("'{}' is a {} law; this object needs a {} law", law.AsString(),
                         material->family(), family));
  return material;
}

void RegisterIntegrators(TypeRegistry& registry) {
  registry.integrators.Register(
      "ExplicitEuler", [] { return std::make_unique<ExplicitEuler>(); },
      "forward Euler, first order");
  registry.integrators.Register(
      "SymplecticEuler", [] { return std::make_unique<SymplecticEuler>(); },
      "semi-implicit Euler for mechanical systems, first order, energy stays bounded");
  registry.integrators.Register(
      "RK4", [] { return std::make_unique<RungeKutta4>(); }, "classic Runge-Kutta, fourth order");
  registry.integrators.Register(
      "BackwardEuler", [] { return std::make_unique<BackwardEulerOde>(); },
      "implicit Euler, first order, no stability limit; Newton with matrix-free GMRES (the model "
      "provides only its derivative)");
}

namespace {

/// A plugin's ABI number in words (GIPSI_PLUGIN_ABI_VERSION's encoding; numbers below 1000 are
/// the bare interface numbers of releases before the package version was part of it).
std::string DescribeAbi(int v) {
  if (v < 1000) return fmt::format("plugin interface {} (an older gipsi)", v);
  return fmt::format("gipsi {}.{} with plugin interface {}", v / 1000000, v / 1000 % 1000,
                     v % 1000);
}

}  // namespace

void TypeRegistry::LoadPlugin(const std::string& path) {
  std::error_code ec;
  std::string canonical = std::filesystem::weakly_canonical(path, ec).string();
  if (ec) canonical = path;
  if (std::find(plugins_.begin(), plugins_.end(), canonical) != plugins_.end()) return;
  if (!std::filesystem::exists(canonical)) ThrowInputError(path, "", "plugin file not found");
  // Never dlclose: objects created by the plugin's factories must keep their code.
  void* handle = dlopen(canonical.c_str(), RTLD_NOW | RTLD_LOCAL);
  if (!handle) ThrowInputError(path, "", fmt::format("cannot load plugin: {}", dlerror()));
  auto version = reinterpret_cast<int (*)()>(dlsym(handle, "gipsi_plugin_abi_version"));
  auto registrar =
      reinterpret_cast<void (*)(TypeRegistry&)>(dlsym(handle, "gipsi_register_plugin"));
  if (!version || !registrar)
    ThrowInputError(path, "",
                    "not a GiPSi plugin: it must export gipsi_plugin_abi_version() and "
                    "gipsi_register_plugin(gipsi::TypeRegistry&)");
  if (const int v = version(); v != GIPSI_PLUGIN_ABI_VERSION)
    ThrowInputError(path, "",
                    fmt::format("plugin built for {}, this is gipsi {}.{} with plugin interface "
                                "{}; rebuild the plugin against this gipsi",
                                DescribeAbi(v), GIPSI_VERSION_MAJOR, GIPSI_VERSION_MINOR,
                                GIPSI_PLUGIN_INTERFACE));
  // A name registered twice aborts in FactoryTable::Register (a programmer error among the
  // built-ins); from a plugin it is bad input, e.g. two copies of one plugin. Register into an
  // empty registry first and refuse a plugin whose names are taken, before it changes this one.
  TypeRegistry scratch;
  registrar(scratch);
  std::vector<std::string> taken;
  auto collect = [&](std::string_view kind, const std::vector<std::string>& ours,
                     const std::vector<std::string>& theirs) {
    for (const auto& name : theirs)
      if (std::find(ours.begin(), ours.end(), name) != ours.end())
        taken.push_back(fmt::format("{} '{}'", kind, name));
  };
  auto names = [](const std::vector<std::pair<std::string, std::string>>& list) {
    std::vector<std::string> out;
    for (const auto& [name, description] : list) out.push_back(name);
    return out;
  };
  collect("object type", objects.Names(), scratch.objects.Names());
  collect("connector type", connectors.Names(), scratch.connectors.Names());
  collect("integrator", integrators.Names(), scratch.integrators.Names());
  collect("material law", materials.Names(), scratch.materials.Names());
  const std::vector<std::string> kinds = TableKinds();
  for (const auto& kind : scratch.TableKinds())
    if (std::find(kinds.begin(), kinds.end(), kind) != kinds.end())
      collect(kind, names(ListTable(kind)), names(scratch.ListTable(kind)));
  if (!taken.empty())
    ThrowInputError(path, "",
                    fmt::format("the plugin registers {}, already registered by GiPSi or an "
                                "earlier plugin (the same plugin loaded from two files?)",
                                fmt::join(taken, ", ")));
  registrar(*this);
  plugins_.push_back(canonical);
}

}  // namespace gipsi
