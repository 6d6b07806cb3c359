// The cavity code FemSolid and MassSpring share (gipsi/models/wall_cavity.h): both walls built on
// one mesh with one cavity spec see the same cavity, declare the same fields and refuse the same
// mistakes with the same words.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "gipsi/base/error.h"
#include "gipsi/geometry/generators.h"
#include "gipsi/models/fem/fem_solid.h"
#include "gipsi/models/mass_spring/mass_spring.h"
#include "models/fem/fem_test_util.h"

namespace gipsi {
namespace {

using ::testing::HasSubstr;

constexpr double kInner = 0.02, kOuter = 0.03, kHeight = 0.02;

std::shared_ptr<const Mesh> Shell() {
  static const auto mesh =
      std::make_shared<const Mesh>(MakeCylinderShell(kInner, kOuter, kHeight, 0.005));
  return mesh;
}

std::unique_ptr<FemSolid> Fem(std::vector<CavitySpec> cavities) {
  FemParams params = testing::AccurateParams(
      R"({"law": "NeoHookean", "youngs_modulus": 1e5, "poisson_ratio": 0.3})",
      ImplicitSchemeKind::kStatic);
  params.cavities = std::move(cavities);
  return std::make_unique<FemSolid>("fem", Shell(), std::move(params));
}

std::unique_ptr<MassSpring> Springs(std::vector<CavitySpec> cavities) {
  MassSpringParams params;
  params.cavities = std::move(cavities);
  return std::make_unique<MassSpring>("springs", Shell(), params,
                                      std::make_unique<SymplecticEuler>());
}

std::string Error(const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "no error";
}

/// A law that is never asked (the walls are not stepped here).
struct Unused final : CavityLaw {
  bool EndVolume(double, double, double, double&) override { return false; }
};

TEST(WallCavity, BothWallsSeeTheSameCavityAndDeclareTheSameFields) {
  const std::vector<CavitySpec> specs = {{"lumen", GroupRegion{"inner"}}};
  auto fem = Fem(specs);
  auto springs = Springs(specs);
  // The open lumen, capped at both rims: the volume of the polygonal cylinder, within the
  // facetting of a 5 mm mesh on a 20 mm radius (about 1 %).
  const double cylinder = std::numbers::pi * kInner * kInner * kHeight;
  EXPECT_NEAR(fem->CavityVolume(0), cylinder, 0.02 * cylinder);
  EXPECT_EQ(fem->CavityVolume(0), springs->CavityVolume(0));  // the same code, the same bits
  for (const char* name : {"lumen_volume", "lumen_pressure"}) {
    const FieldInfo& a = fem->field_info(fem->FindField(name));
    const FieldInfo& b = springs->field_info(springs->FindField(name));
    EXPECT_EQ(a.units, b.units) << name;
    EXPECT_EQ(a.access, b.access) << name;
    EXPECT_EQ(a.location, FieldLocation::kGlobal) << name;
  }
  EXPECT_EQ(fem->cavity_names(), std::vector<std::string>{"lumen"});
  EXPECT_EQ(springs->cavity_names(), std::vector<std::string>{"lumen"});
}

TEST(WallCavity, BothWallsRefuseTheSameMistakesInTheSameWords) {
  const std::vector<CavitySpec> specs = {{"lumen", GroupRegion{"inner"}}};
  auto fem = Fem(specs);
  auto springs = Springs(specs);
  Unused law;
  EXPECT_EQ(Error([&] { fem->AttachCavityLaw("lv", &law); }),
            "object 'fem' (FemSolid) has no cavity 'lv'; its cavities: lumen");
  EXPECT_EQ(Error([&] { springs->AttachCavityLaw("lv", &law); }),
            "object 'springs' (MassSpring) has no cavity 'lv'; its cavities: lumen");
  fem->AttachCavityLaw("lumen", &law);
  springs->AttachCavityLaw("lumen", &law);
  EXPECT_EQ(Error([&] { fem->AttachCavityLaw("lumen", &law); }),
            "object 'fem': cavity 'lumen' is already coupled to blood");
  EXPECT_EQ(Error([&] { springs->AttachCavityLaw("lumen", &law); }),
            "object 'springs': cavity 'lumen' is already coupled to blood");
  // A region that selects no boundary face.
  const std::vector<CavitySpec> empty = {{"void", SphereRegion{Vec3(1, 1, 1), 0.001}}};
  EXPECT_EQ(Error([&] { (void)Fem(empty); }),
            "object 'fem': cavity 'void' selects no boundary face");
  EXPECT_EQ(Error([&] { (void)Springs(empty); }),
            "object 'springs': cavity 'void' selects no boundary face");
}

}  // namespace
}  // namespace gipsi
