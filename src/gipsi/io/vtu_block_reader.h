#pragma once
/// @file
/// Reading one process's block of a VTK XML unstructured grid (`.vtu`; geometry/mesh_block.h)
/// without holding the whole mesh or the whole file, for objects split over the processes of a
/// distributed run, as gmsh_block_reader.h does for Gmsh files.

#include <filesystem>
#include <optional>

#include "gipsi/base/export.h"
#include "gipsi/geometry/mesh_block.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// Block `rank` of `size` of the `.vtu` file at `path`: the same block as
/// BlockOfMesh(ReadVtu(path), rank, size) (nodes, tets and triangles; the file has no groups or
/// element ids that ReadVtu reads). Reads every array layout ReadVtu reads (ascii, inline base64
/// and appended raw or base64 data, zlib-compressed or not, either header type and byte order),
/// streaming: a first pass copies the XML markup without the arrays' data and parses it, then
/// each array is decoded front to back through its own small buffer, its values checked as
/// ReadVtu checks them and only the block's kept. Memory: the block, the markup, a few buffers of
/// at most 1 MiB, and a compressed array's block sizes (8 bytes a block).
///
/// Returns nothing for a file it does not read in blocks: more than one `<Piece>`, quadratic
/// cells (types 24 and 22, whose middle points ReadVtu takes out of the node numbering) or a
/// CDATA section: read such a file whole (ReadMesh) and slice it. Throws InputError naming the
/// file and the line of the offending XML element for the errors ReadVtu reports, with its
/// message where it can (a file with several errors may have another named first); the block is
/// not passed through Mesh::Validate, which needs the whole mesh.
std::optional<MeshBlock> ReadVtuBlock(const std::filesystem::path& path, int rank, int size);

}  // namespace gipsi
GIPSI_EXPORT_END
