#pragma once
/// @file
/// Internal: the Gmsh element types the mesh readers know (gmsh_reader.h, gmsh_block_reader.h).
/// Not part of the public API.

#include <cstdint>

#include "gipsi/base/export.h"

GIPSI_EXPORT_BEGIN
namespace gipsi::internal {

/// Number of nodes and dimension of a Gmsh element type; nodes = -1 for unknown types.
struct ElementInfo {
  int nodes = -1;
  int dim = -1;
  const char* name = "element";
};

inline ElementInfo GetElementInfo(std::int64_t type) {
  switch (type) {
    case 1:
      return {2, 1, "line"};
    case 2:
      return {3, 2, "triangle"};
    case 3:
      return {4, 2, "quadrangle"};
    case 4:
      return {4, 3, "tetrahedron"};
    case 5:
      return {8, 3, "hexahedron"};
    case 6:
      return {6, 3, "prism"};
    case 7:
      return {5, 3, "pyramid"};
    case 8:
      return {3, 1, "second-order line"};
    case 9:
      return {6, 2, "second-order triangle"};
    case 10:
      return {9, 2, "second-order quadrangle"};
    case 11:
      return {10, 3, "second-order tetrahedron"};
    case 12:
      return {27, 3, "second-order hexahedron"};
    case 13:
      return {18, 3, "second-order prism"};
    case 14:
      return {14, 3, "second-order pyramid"};
    case 15:
      return {1, 0, "point"};
    case 16:
      return {8, 2, "8-node quadrangle"};
    case 17:
      return {20, 3, "20-node hexahedron"};
    case 18:
      return {15, 3, "15-node prism"};
    case 19:
      return {13, 3, "13-node pyramid"};
    case 20:
      return {9, 2, "9-node triangle"};
    case 21:
      return {10, 2, "10-node triangle"};
    case 22:
      return {12, 2, "12-node triangle"};
    case 23:
      return {15, 2, "15-node triangle"};
    case 24:
      return {15, 2, "15-node triangle"};
    case 25:
      return {21, 2, "21-node triangle"};
    case 26:
      return {4, 1, "4-node line"};
    case 27:
      return {5, 1, "5-node line"};
    case 28:
      return {6, 1, "6-node line"};
    case 29:
      return {20, 3, "20-node tetrahedron"};
    case 30:
      return {35, 3, "35-node tetrahedron"};
    case 31:
      return {56, 3, "56-node tetrahedron"};
    default:
      return {};
  }
}

}  // namespace gipsi::internal
GIPSI_EXPORT_END
