#include "gipsi/models/mass_spring/spring_law.h"

namespace gipsi {

void RegisterSpringLaws(TypeRegistry& registry) {
  registry.materials.Register(
      "Hooke",
      [](const JsonNode& node) -> std::shared_ptr<const Material> {
        node.CheckKeys({"law"});
        return std::make_shared<HookeSpring>();
      },
      "spring law: linear tension k (L - L0)");
  registry.materials.Register(
      "Exponential",
      [](const JsonNode& node) -> std::shared_ptr<const Material> {
        node.CheckKeys({"law", "b"});
        return std::make_shared<ExponentialSpring>(node.Positive("b"));
      },
      "spring law: strain-stiffening tension (k L0 / b)(exp(b strain) - 1)");
}

}  // namespace gipsi
