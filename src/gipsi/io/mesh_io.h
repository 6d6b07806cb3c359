#pragma once
/// @file
/// Reading and writing meshes by file extension: the entry point the rest of GiPSi uses.

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "gipsi/geometry/mesh.h"

namespace gipsi {

/// Reads a mesh, choosing the reader by the (case-insensitive) extension of `path`:
///  - `.msh`: Gmsh 1.0, 2.x, 4.1 ASCII/binary (`ReadGmsh`);
///  - `.node`, `.ele`, `.face`: TetGen files sharing the stem (`ReadTetGen`);
///  - `.vtk`: legacy VTK (`ReadVtkLegacy`);
///  - `.vtu`: VTK XML unstructured grid (`ReadVtu`);
///  - `.obj`: Wavefront OBJ surface (`ReadObj`);
///  - `.stl`: STL surface, ASCII or binary, vertices welded with the default tolerance (`ReadStl`).
/// Throws InputError for an unknown extension (listing the supported ones), a missing file or
/// any format error (see each reader). The result has passed `Mesh::Validate`.
Mesh ReadMesh(const std::filesystem::path& path);

/// How a mesh file names its tets, for messages: `tets[e]` is the file's own id of tet e (Gmsh:
/// its element tag), and `kind` says what the ids are. Plain struct.
struct MeshFileIds {
  std::vector<std::int64_t> tets;
  std::string kind;  ///< e.g. "Gmsh element tags"; empty when the file has no ids of its own
  /// Tet `e`'s id in the file, or `e` itself (the 0-based index in the mesh) without them.
  [[nodiscard]] std::int64_t Tet(Index e) const {
    return tets.empty() ? e : tets[static_cast<std::size_t>(e)];
  }
};

/// ReadMesh, also filling `ids` with the file's own tet ids where the format has them (Gmsh
/// element tags); for the other formats `ids->tets` stays empty and `ids->kind` says the ids
/// are 0-based indices in file order.
Mesh ReadMesh(const std::filesystem::path& path, MeshFileIds* ids);

/// Writes `mesh`, choosing the writer by the (case-insensitive) extension of `path`:
///  - `.vtu`: tets and triangles as one unstructured grid (`WriteVtu`);
///  - `.obj`: the triangles (`WriteObj`);
///  - `.stl`: the triangles, binary STL (`WriteStl`).
/// Throws InputError for an unknown extension, when `.obj`/`.stl` is asked for a mesh without
/// triangles, or when the file cannot be written.
void WriteMesh(const std::filesystem::path& path, const Mesh& mesh);

}  // namespace gipsi
