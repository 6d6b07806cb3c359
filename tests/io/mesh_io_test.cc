#include "gipsi/io/mesh_io.h"

#include <random>
#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "io/io_test_util.h"

namespace gipsi {
namespace {

using test::InputErrorMessage;
using test::MeshData;
using test::Scratch;
using ::testing::HasSubstr;

TEST(MeshIo, ReadMeshDispatchesOnExtension) {
  EXPECT_EQ(ReadMesh(MeshData("two_tets_v22.msh")).num_tets(), 2);
  EXPECT_EQ(ReadMesh(MeshData("two_tets.ele")).num_tets(), 2);
  EXPECT_EQ(ReadMesh(MeshData("two_tets_ascii.vtk")).num_tets(), 2);
  EXPECT_EQ(ReadMesh(MeshData("two_tets_ascii.vtu")).num_tets(), 2);
  EXPECT_EQ(ReadMesh(MeshData("cube_surface.obj")).num_triangles(), 12);
  EXPECT_EQ(ReadMesh(MeshData("cube_ascii.stl")).num_nodes(), 8);
}

TEST(MeshIo, ReadMeshIgnoresExtensionCase) {
  auto upper = Scratch("CUBE.OBJ");
  std::filesystem::copy_file(MeshData("cube_surface.obj"), upper,
                             std::filesystem::copy_options::overwrite_existing);
  EXPECT_EQ(ReadMesh(upper).num_triangles(), 12);
}

TEST(MeshIo, RejectsUnknownExtensionListingSupportedOnes) {
  EXPECT_EQ(InputErrorMessage([] { ReadMesh("organ.ply"); }),
            "organ.ply: unknown mesh file extension '.ply' (supported: .msh, .node/.ele "
            "(TetGen), .vtk, .vtu, .obj, .stl)");
}

TEST(MeshIo, RejectsMissingFile) {
  EXPECT_EQ(InputErrorMessage([] { ReadMesh("/nonexistent/organ.msh"); }),
            "/nonexistent/organ.msh: cannot open mesh file for reading: No such file or directory");
}

TEST(MeshIo, WriteMeshRoundTripsEveryWritableFormat) {
  Mesh cube = ReadMesh(MeshData("cube_surface.obj"));
  for (const char* name : {"cube.vtu", "cube.obj"}) {
    auto path = Scratch(name);
    WriteMesh(path, cube);
    Mesh back = ReadMesh(path);
    EXPECT_EQ(back.nodes, cube.nodes) << name;
    EXPECT_EQ(back.triangles, cube.triangles) << name;
  }
  // STL renumbers vertices in order of first appearance.
  WriteMesh(Scratch("cube.stl"), cube);
  Mesh stl = ReadMesh(Scratch("cube.stl"));
  EXPECT_EQ(stl.num_nodes(), 8);
  ASSERT_EQ(stl.num_triangles(), 12);
  for (Index t = 0; t < 12; ++t)
    for (Index k = 0; k < 3; ++k)
      EXPECT_EQ(stl.nodes.col(stl.triangles(k, t)), cube.nodes.col(cube.triangles(k, t)));
  Mesh tets = ReadMesh(MeshData("two_tets_v41.msh"));
  WriteMesh(Scratch("tets.vtu"), tets);
  EXPECT_EQ(ReadMesh(Scratch("tets.vtu")).tets, tets.tets);
}

TEST(MeshIo, WriteMeshRejectsSurfaceFormatForTetOnlyMesh) {
  Mesh tets = ReadMesh(test::SharedData("liver/liver.msh"));
  EXPECT_THAT(InputErrorMessage([&] { WriteMesh(Scratch("liver.stl"), tets); }),
              HasSubstr("cannot write a mesh without triangles as .stl"));
  EXPECT_THAT(InputErrorMessage([&] { WriteMesh(Scratch("liver.ply"), tets); }),
              HasSubstr("unknown mesh file extension '.ply' for writing"));
}

TEST(MeshIo, SurvivesRandomByteCorruptionOfEveryFormat) {
  // Each corrupted file either fails with InputError or yields a mesh that passes Validate.
  std::mt19937 rng(1234);
  for (const char* name : {"two_tets_v22.msh", "two_tets_v41.msh", "single_tet_v1.msh",
                           "two_tets_ascii.vtk", "two_tets_v51.vtk", "cube_quads.vtk",
                           "two_tets_ascii.vtu", "cube_surface.obj", "cube_ascii.stl"}) {
    const std::string original = test::ReadBytes(MeshData(name));
    std::uniform_int_distribution<std::size_t> where(0, original.size() - 1);
    std::uniform_int_distribution<int> byte(0, 255);
    const char* digits = "0123456789-.e $\n";
    auto path = Scratch(name);
    for (int trial = 0; trial < 300; ++trial) {
      std::string bytes = original;
      for (int k = 0; k < 1 + trial % 3; ++k) {
        char c = trial % 2 ? static_cast<char>(byte(rng)) : digits[byte(rng) % 16];
        bytes[where(rng)] = c;
      }
      if (trial % 5 == 0) bytes.resize(where(rng));
      test::WriteBytes(path, bytes);
      try {
        ReadMesh(path).Validate(name);
      } catch (const InputError&) {
      }
    }
  }
}

}  // namespace
}  // namespace gipsi
