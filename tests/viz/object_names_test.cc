// One naming scheme for objects (issue 22): the full dotted name of a part of an aggregate
// ("tissue.upper") everywhere — scenes, probes, --color, --as, --show, --hide, the viewer's
// panel, the drawn buffers and error messages — and the part's own name ("upper") wherever it is
// unambiguous. Kernel::FindObject is the one resolver behind all of them.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "gipsi/base/error.h"
#include "gipsi/io/builtins.h"
#include "gipsi/io/scene.h"
#include "gipsi/viz/display_manager.h"

namespace gipsi::viz {
namespace {

using ::testing::HasSubstr;

/// An aggregate "tissue" of two blocks "upper" and "lower", and a third block also called
/// "lower" inside another aggregate "other" when `twin`.
Scene LoadTissue(TypeRegistry& registry, bool twin = false) {
  RegisterBuiltins(registry);
  const std::string block = R"({"type": "MassSpring", "domain": "box", "stiffness": 2000,
                                 "dt": 0.001})";
  std::string other;
  if (twin)
    other = R"(, "other": {"type": "Aggregate", "dt": 0.001, "parts": {"lower": )" + block + "}}";
  return LoadSceneFromString(R"({
    "meshes": {"box": {"generate": "box", "min": [0, 0, 0], "max": [1, 1, 1], "cells": [1, 1, 1]}},
    "objects": {"tissue": {"type": "Aggregate", "dt": 0.001,
                           "parts": {"upper": )" +
                                 block + R"(, "lower": )" + block + R"(}})" + other + R"(},
    "schedule": {"end": 0.01},
    "probes": {"by_short_name": {"object": "upper", "fields": ["kinetic_energy"]}}
  })",
                             "tissue.json", ".", registry);
}

ColorSpec FieldColor(const std::string& field) {
  ColorSpec spec;
  spec.field = field;
  return spec;
}

std::string Message(const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "no error";
}

TEST(ObjectNames, AFullDottedNameAndAnUnambiguousShortNameFindTheSamePart) {
  TypeRegistry registry;
  Scene scene = LoadTissue(registry);
  const Kernel& kernel = *scene.kernel;
  SimObject& upper = kernel.FindObject("tissue.upper");
  EXPECT_EQ(&kernel.FindObject("upper"), &upper);
  EXPECT_EQ(kernel.ObjectPath(upper), "tissue.upper");
  // The probe in the scene named it by its short name.
  ASSERT_EQ(scene.probes.size(), 1u);
  EXPECT_EQ(scene.probes[0].object, &upper);
  // An unknown name lists every object and part by its full name.
  EXPECT_THAT(Message([&] { (void)kernel.FindObject("uper"); }),
              HasSubstr("no object named 'uper' (did you mean 'upper'?); objects: tissue, "
                        "tissue.upper, tissue.lower"));
}

TEST(ObjectNames, AnAmbiguousShortNameNamesItsCandidates) {
  TypeRegistry registry;
  Scene scene = LoadTissue(registry, true);
  EXPECT_EQ(Message([&] { (void)scene.kernel->FindObject("lower"); }),
            "object name 'lower' is ambiguous: it could be tissue.lower or other.lower");
  EXPECT_EQ(&scene.kernel->FindObject("other.lower"), scene.kernel->ObjectPaths().back().second);
}

TEST(ObjectNames, MessagesNameAPartByItsFullName) {
  // Scene-load messages named a part by its own name ("object 'muscle': its time step ..."),
  // which the command line then refused or found ambiguous.
  TypeRegistry registry;
  Scene scene = LoadTissue(registry, true);
  const SimObject& lower = scene.kernel->FindObject("other.lower");
  EXPECT_EQ(lower.name(), "lower");  // its key, for orders and connectors
  EXPECT_EQ(lower.path(), "other.lower");
  EXPECT_EQ(scene.kernel->FindObject("tissue").path(), "tissue");
  const auto load = [&](const std::string& parts) {
    return Message([&] {
      TypeRegistry fresh;
      RegisterBuiltins(fresh);
      (void)LoadSceneFromString(R"({
        "meshes": {"box": {"generate": "box", "min": [0, 0, 0], "max": [1, 1, 1],
                           "cells": [1, 1, 1]}},
        "objects": {"outer": {"type": "Aggregate", "dt": 0.001, "parts": {"inner": {
          "type": "Aggregate", "dt": 0.001, "parts": )" +
                                    parts + R"(}}}},
        "schedule": {"end": 0.01}})",
                                "nested.json", ".", fresh);
    });
  };
  // Nested aggregates: the path runs from the top level, for a part (its time step) and for a
  // connector (its wiring).
  EXPECT_THAT(load(R"({"block": {"type": "MassSpring", "domain": "box", "stiffness": 2000,
                                   "dt": 0.003}})"),
              HasSubstr("object 'outer.inner.block': its time step 0.003 s does not divide"));
  // A connector of the nested aggregate, wired to a field of other units.
  const std::string block = R"({"type": "MassSpring", "domain": "box", "stiffness": 2000,
                                 "dt": 0.001})";
  EXPECT_THAT(load(R"({"a": )" + block + R"(, "b": )" + block + R"(},
                       "connectors": {"copy": {"type": "FieldCopy", "from": "a.kinetic_energy",
                                               "to": "b.external_force"}})"),
              HasSubstr("connector 'outer.inner.copy'"));
}

TEST(ObjectNames, DrawnObjectsCarryTheirFullNamesAndTheOptionsTakeEitherName) {
  TypeRegistry registry;
  Scene scene = LoadTissue(registry);
  const Kernel& kernel = *scene.kernel;
  // --color with the short name, and with the full one: the same object.
  for (const char* name : {"upper", "tissue.upper"}) {
    SceneDisplay display(kernel, {{name, FieldColor("displacement")}});
    ASSERT_EQ(display.size(), 2u);
    EXPECT_EQ(display.manager(0).name(), "tissue.upper");
    EXPECT_EQ(display.manager(1).name(), "tissue.lower");
    EXPECT_EQ(display.manager(0).spec().field, "displacement") << name;
    FrameBuffers frame;
    display.Fill(0, frame);
    EXPECT_EQ(frame.surfaces[0].object, "tissue.upper");
  }
  // --hide and --show with either name (before, --hide took only the short name and --color
  // only the full one).
  const std::vector<std::string> names{"tissue.upper", "tissue.lower"};
  std::vector<bool> hidden;
  ApplyVisibility(kernel, names, {}, {"tissue.upper", "lower"}, hidden);
  EXPECT_EQ(hidden, (std::vector<bool>{true, true}));
  ApplyVisibility(kernel, names, {"upper"}, {}, hidden);
  EXPECT_EQ(hidden, (std::vector<bool>{false, true}));
  EXPECT_THAT(Message([&] { ApplyVisibility(kernel, names, {}, {"tissue"}, hidden); }),
              HasSubstr("--hide: object 'tissue' is not drawn; drawn: tissue.upper, tissue.lower"));
  EXPECT_THAT(Message([&] { ApplyVisibility(kernel, names, {"lowr"}, {}, hidden); }),
              HasSubstr("--show: no object named 'lowr' (did you mean 'lower'?)"));
  // Errors about a drawn object name it by its full name.
  EXPECT_THAT(Message([&] {
                SceneDisplay(kernel, {{"upper", FieldColor("Vm")}});
              }),
              HasSubstr("'tissue.upper'"));
}

TEST(SceneDisplay, ItsColoursRedrawAReloadedSceneTheSameWay) {
  // The viewer's reset reloads the scene; drawing it with the old display's Colors() keeps the
  // colouring chosen in the panel (before, the reload fell back to the command line's colours
  // while the panel still showed the chosen field).
  TypeRegistry registry, registry2;
  Scene scene = LoadTissue(registry), reloaded = LoadTissue(registry2);
  SceneDisplay display(*scene.kernel, {});
  DrawSpec draw = display.manager(1).draw();
  draw.color.field = "velocity";
  draw.color.component = 2;
  display.manager(1) = DisplayManager(display.manager(1).object(), draw, display.manager(1).name());
  SceneDisplay again(*reloaded.kernel, reloaded.display, display.Colors());
  ASSERT_EQ(again.size(), 2u);
  EXPECT_EQ(again.manager(1).spec().field, "velocity");
  EXPECT_EQ(again.manager(1).spec().component, 2);
  EXPECT_EQ(again.manager(0).spec().field, "");
  EXPECT_EQ(again.manager(0).spec().solid.r, display.manager(0).spec().solid.r);
  FrameBuffers frame;
  again.Fill(0, frame);
  EXPECT_EQ(frame.surfaces[1].field, "velocity z");
}

}  // namespace
}  // namespace gipsi::viz
