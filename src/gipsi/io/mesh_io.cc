#include "gipsi/io/mesh_io.h"

#include <algorithm>
#include <cctype>
#include <string>

#include <fmt/format.h>

#include "gipsi/base/error.h"
#include "gipsi/io/gmsh_reader.h"
#include "gipsi/io/obj_io.h"
#include "gipsi/io/stl_io.h"
#include "gipsi/io/tetgen_reader.h"
#include "gipsi/io/vtk_legacy_reader.h"
#include "gipsi/io/vtu_reader.h"
#include "gipsi/io/vtu_writer.h"

namespace gipsi {
namespace {

std::string LowerExtension(const std::filesystem::path& path) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext;
}

/// The reader for `path`'s extension; Gmsh files also give their tet tags.
Mesh ReadByExtension(const std::filesystem::path& path) {
  const std::string ext = LowerExtension(path);
  if (ext == ".msh") {
    std::vector<std::int64_t> tags;
    Mesh mesh = ReadGmsh(path, &tags);
    mesh.tet_ids = std::move(tags);
    mesh.tet_id_kind = "Gmsh element tag";
    return mesh;
  }
  if (ext == ".node" || ext == ".ele" || ext == ".face") return ReadTetGen(path);
  if (ext == ".vtk") return ReadVtkLegacy(path);
  if (ext == ".vtu") return ReadVtu(path);
  if (ext == ".obj") return ReadObj(path);
  if (ext == ".stl") return ReadStl(path);
  ThrowInputError(path.string(), "",
                  fmt::format("unknown mesh file extension '{}' (supported: .msh, .node/.ele "
                              "(TetGen), .vtk, .vtu, .obj, .stl)",
                              path.extension().string()));
}

}  // namespace

Mesh ReadMesh(const std::filesystem::path& path) {
  Mesh mesh = ReadByExtension(path);
  // Some formats (OBJ) skip lines they do not know, so a file of another format, or an empty
  // one, reads as a mesh without nodes: never what was meant.
  if (mesh.num_nodes() == 0)
    ThrowInputError(path.string(), "",
                    fmt::format("the file holds no nodes: an empty mesh, or not a {} file",
                                path.extension().string()));
  return mesh;
}

void WriteMesh(const std::filesystem::path& path, const Mesh& mesh) {
  const std::string ext = LowerExtension(path);
  if (ext == ".vtu") {
    WriteVtu(path, mesh);
    return;
  }
  if (ext != ".obj" && ext != ".stl") {
    ThrowInputError(path.string(), "",
                    fmt::format("unknown mesh file extension '{}' for writing (supported: .vtu, "
                                ".obj, .stl)",
                                path.extension().string()));
  }
  if (mesh.num_triangles() == 0) {
    ThrowInputError(path.string(), "",
                    fmt::format("cannot write a mesh without triangles as {} (write .vtu, or "
                                "extract the boundary surface first)",
                                ext));
  }
  if (ext == ".obj")
    WriteObj(path, mesh.nodes, mesh.triangles);
  else
    WriteStl(path, mesh.nodes, mesh.triangles, StlFormat::kBinary);
}

}  // namespace gipsi
