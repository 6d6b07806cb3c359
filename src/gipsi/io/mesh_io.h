#pragma once
/// @file
/// Reading and writing meshes by file extension: the entry point the rest of GiPSi uses.

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "gipsi/base/export.h"
#include "gipsi/geometry/mesh.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// Reads a mesh, choosing the reader by the (case-insensitive) extension of `path`:
///  - `.msh`: Gmsh 1.0, 2.x, 4.1 ASCII/binary (`ReadGmsh`);
///  - `.node`, `.ele`, `.face`: TetGen files sharing the stem (`ReadTetGen`);
///  - `.vtk`: legacy VTK (`ReadVtkLegacy`);
///  - `.vtu`: VTK XML unstructured grid (`ReadVtu`);
///  - `.obj`: Wavefront OBJ surface (`ReadObj`);
///  - `.stl`: STL surface, ASCII or binary, vertices welded with the default tolerance (`ReadStl`).
/// Throws InputError for an unknown extension (listing the supported ones), a missing file or
/// any format error (see each reader). The result has passed `Mesh::Validate`. Gmsh files also
/// give their element tags as `Mesh::tet_ids`, so messages name tets as the file does.
Mesh ReadMesh(const std::filesystem::path& path);

/// Writes `mesh`, choosing the writer by the (case-insensitive) extension of `path`:
///  - `.vtu`: tets and triangles as one unstructured grid (`WriteVtu`);
///  - `.obj`: the triangles (`WriteObj`);
///  - `.stl`: the triangles, binary STL (`WriteStl`).
/// Throws InputError for an unknown extension, when `.obj`/`.stl` is asked for a mesh without
/// triangles, or when the file cannot be written.
void WriteMesh(const std::filesystem::path& path, const Mesh& mesh);

}  // namespace gipsi
GIPSI_EXPORT_END
