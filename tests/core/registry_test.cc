// The type registry's tables of further product kinds (TypeRegistry::Table): a layer above the
// kernel declares its own kind of factory without the kernel naming it.

#include "gipsi/core/registry.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "gipsi/base/error.h"
#include "gipsi/io/builtins.h"

namespace gipsi {
namespace {

using ::testing::ElementsAre;
using ::testing::HasSubstr;
using ::testing::Pair;

// A product kind the kernel knows nothing about, as a plugin would declare it.
using GreeterFactory = std::function<std::string(const std::string&)>;
FactoryTable<GreeterFactory>& Greeters(TypeRegistry& registry) {
  return registry.Table<GreeterFactory>("greeter");
}

TEST(TypeRegistryTables, AKindDeclaredAboveTheKernelRegistersListsAndCreates) {
  TypeRegistry registry;
  Greeters(registry).Register(
      "Hello", [](const std::string& who) { return "hello " + who; }, "says hello");
  Greeters(registry).Register(
      "Bye", [](const std::string& who) { return "bye " + who; }, "says bye");

  const TypeRegistry& read_only = registry;
  const auto& table = read_only.Table<GreeterFactory>("greeter");
  const JsonDocument doc = JsonDocument::Parse("{}", "scene.json");
  EXPECT_EQ(table.Get("Hello", doc.root())("you"), "hello you");
  EXPECT_THAT(registry.TableKinds(), ElementsAre("greeter"));
  EXPECT_THAT(registry.ListTable("greeter"),
              ElementsAre(Pair("Bye", "says bye"), Pair("Hello", "says hello")));
}

TEST(TypeRegistryTables, AnUnknownNameIsRefusedAtItsJsonPathListingTheKnownOnes) {
  TypeRegistry registry;
  Greeters(registry).Register(
      "Hello", [](const std::string& who) { return who; }, "");
  const JsonDocument doc = JsonDocument::Parse(R"({"greet": {"type": "Helo"}})", "scene.json");
  const JsonNode scene = doc.root();
  try {
    (void)Greeters(registry).Get("Helo", scene.At("greet").At("type"));
    FAIL() << "expected an InputError";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("scene.json"));
    EXPECT_THAT(e.what(), HasSubstr("greet.type"));
    EXPECT_THAT(e.what(), HasSubstr("unknown greeter 'Helo'"));
    EXPECT_THAT(e.what(), HasSubstr("Hello"));
  }
}

TEST(TypeRegistryTables, TheBuiltinsDeclareCellModelsAndHapticLocalModelsAsTables) {
  TypeRegistry registry;
  RegisterBuiltins(registry);
  EXPECT_THAT(registry.TableKinds(), ElementsAre("cell model", "haptic local model"));
  std::vector<std::string> local_models;
  for (const auto& [name, description] : registry.ListTable("haptic local model"))
    local_models.push_back(name);
  EXPECT_THAT(local_models, ElementsAre("FemSolid", "MassSpring"));
}

}  // namespace
}  // namespace gipsi
