// Objects a distributed scene run makes in blocks on one mesh share its cut
// (parallel/distributed_types.cc): the mesh's blocks are read and partitioned once, and the
// objects' parts are the same part (one part mesh, split alike). A scene loaded later with the
// same registry cuts its own meshes, even under the same names. Runs under `mpiexec -np 2` and
// `-np 4 --oversubscribe` (tests/CMakeLists.txt); every test is collective.

#include <gtest/gtest.h>
#include <mpi.h>

#include <memory>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "gipsi/core/kernel.h"
#include "gipsi/core/partitioned_object.h"
#include "gipsi/io/builtins.h"
#include "gipsi/io/scene.h"
#include "gipsi/parallel/distributed_types.h"
#include "gipsi/parallel/parallel_session.h"

namespace gipsi {
namespace {

// Bioelectricity and a muscle on one box of `cells` cells (6 tets each), coupled part to part,
// so both are made in blocks.
std::string SceneText(int cells) {
  return fmt::format(R"({{
    "gipsi": 1, "units": "SI",
    "meshes": {{"box": {{"generate": "box", "min": [0, 0, 0], "max": [0.01, 0.004, 0.002],
                         "cells": [{}, 4, 2]}}}},
    "objects": {{
      "ep": {{"type": "Monodomain", "domain": "box", "dt": "0.1 ms",
              "cell": {{"model": "AlievPanfilov"}}, "conductivity": "0.1 S/m",
              "surface_to_volume": "140 1/mm", "capacitance": "1 uF/cm^2"}},
      "muscle": {{"type": "FemSolid", "domain": "box", "dt": "0.1 ms", "density": 1000,
                  "material": {{"law": "Corotational", "youngs_modulus": 1e5,
                                "poisson_ratio": 0.45}},
                  "integrator": "BackwardEuler"}}
    }},
    "connectors": {{"ec": {{"type": "ExcitationContraction", "from": "ep.V",
                            "to": "muscle.active_tension"}}}},
    "schedule": {{"end": 0.001}}
  }})",
                     cells);
}

TEST(SceneCuts, ObjectsOnOneMeshShareItsCut) {
  TypeRegistry registry;
  RegisterBuiltins(registry);
  auto split = std::make_shared<std::vector<std::string>>();
  RegisterDistributedTypes(registry, ParallelSession::world(), split);
  Scene first = LoadSceneFromString(SceneText(10), "cuts.json", ".", registry);
  EXPECT_EQ(*split, (std::vector<std::string>{"ep (Monodomain, in blocks)",
                                              "muscle (FemSolid, in blocks)"}));
  auto& ep = dynamic_cast<PartitionedObject&>(first.kernel->FindObject("ep"));
  auto& muscle = dynamic_cast<PartitionedObject&>(first.kernel->FindObject("muscle"));
  EXPECT_EQ(&ep.local_part().domain(), &muscle.local_part().domain());  // one part mesh
  EXPECT_TRUE(SplitAlike(first.kernel->FindObject("ep"), first.kernel->FindObject("muscle")));
  EXPECT_EQ(ep.whole_num_tets(), 10 * 4 * 2 * 6);

  // Another scene with the same registry, its box under the same name but finer: cut anew.
  Scene second = LoadSceneFromString(SceneText(12), "cuts.json", ".", registry);
  auto& ep2 = dynamic_cast<PartitionedObject&>(second.kernel->FindObject("ep"));
  auto& muscle2 = dynamic_cast<PartitionedObject&>(second.kernel->FindObject("muscle"));
  EXPECT_EQ(ep2.whole_num_tets(), 12 * 4 * 2 * 6);
  EXPECT_EQ(muscle2.whole_num_tets(), 12 * 4 * 2 * 6);
  EXPECT_EQ(&ep2.local_part().domain(), &muscle2.local_part().domain());
  EXPECT_NE(&ep2.local_part().domain(), &ep.local_part().domain());
  // Both run.
  EXPECT_TRUE(first.kernel->Run(0.0005).ok());
  EXPECT_TRUE(second.kernel->Run(0.0005).ok());
}

}  // namespace
}  // namespace gipsi
