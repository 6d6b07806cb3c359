#pragma once
/// @file
/// Helpers shared by the mesh I/O tests: paths of test inputs, per-test scratch files, byte
/// builders for binary formats, capturing InputError messages, and comparing mesh blocks.

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <string>
#include <string_view>

#include <gtest/gtest.h>

#include "gipsi/base/error.h"
#include "gipsi/geometry/mesh.h"
#include "gipsi/geometry/mesh_block.h"
#include "temp_dir.h"
#include "test_paths.h"

namespace gipsi::test {

/// A hand-written input under tests/data/meshes/.
inline std::filesystem::path MeshData(std::string_view name) {
  return std::filesystem::path(GIPSI_SOURCE_DIR) / "tests" / "data" / "meshes" / name;
}

/// A file of the shared sample data (e.g. "liver/liver.msh").
inline std::filesystem::path SharedData(std::string_view name) {
  return std::filesystem::path(GIPSI_SHARED_DATA_DIR) / name;
}

/// A scratch path unique to the running test and process (tests/temp_dir.h):
/// <temp>/gipsi_test_<pid>/gipsi_io/<Suite>.<Test>/<name>.
inline std::filesystem::path Scratch(std::string_view name) {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  auto dir = gipsi::testing::ProcessTempRoot() / "gipsi_io" /
             (std::string(info->test_suite_name()) + "." + info->name());
  std::filesystem::create_directories(dir);
  return dir / name;
}

/// Writes `bytes` to `path` and returns the path.
inline std::filesystem::path WriteBytes(const std::filesystem::path& path, std::string_view bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  return path;
}

/// Reads a whole file.
inline std::string ReadBytes(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

/// Checks the two-tets-and-a-triangle test mesh that the VTK and VTU inputs describe (5 nodes,
/// tets 0-1-2-3 and 1-2-3-4, triangle 0-1-2).
inline void ExpectTwoTetsAndTriangle(const Mesh& mesh) {
  ASSERT_EQ(mesh.num_nodes(), 5);
  ASSERT_EQ(mesh.num_tets(), 2);
  ASSERT_EQ(mesh.num_triangles(), 1);
  EXPECT_EQ(mesh.nodes.col(4), Vec3(1, 1, 1));
  EXPECT_EQ(mesh.tets.col(1), Eigen::Vector4i(1, 2, 3, 4));
  EXPECT_EQ(mesh.triangles.col(0), Eigen::Vector3i(0, 1, 2));
}

/// Writes every strict prefix of `bytes` to `path` and reads it with `read` (which returns a
/// Mesh). Each prefix must either throw InputError or give the whole file's mesh, or — for a
/// cut exactly between the node and element sections, which is itself a valid node-only file —
/// the whole file's nodes with no elements. Never a partial mesh, another exception, a crash or
/// a sanitizer report. Returns how many prefixes were rejected.
template <class Read>
std::size_t CountRejectedPrefixes(const std::string& bytes, const std::filesystem::path& path,
                                  Read read) {
  WriteBytes(path, bytes);
  const Mesh whole = read(path);
  auto same = [](const auto& a, const auto& b) {
    return a.rows() == b.rows() && a.cols() == b.cols() && a == b;
  };
  std::size_t rejected = 0;
  for (std::size_t n = 0; n < bytes.size(); ++n) {
    WriteBytes(path, std::string_view(bytes).substr(0, n));
    try {
      const Mesh mesh = read(path);
      const bool nodes_only = mesh.num_tets() == 0 && mesh.num_triangles() == 0;
      EXPECT_TRUE(same(mesh.nodes, whole.nodes))
          << "prefix of " << n << " bytes: " << mesh.num_nodes() << " of " << whole.num_nodes()
          << " nodes";
      EXPECT_TRUE(nodes_only ||
                  (same(mesh.tets, whole.tets) && same(mesh.triangles, whole.triangles)))
          << "prefix of " << n << " bytes: " << mesh.num_tets() << " of " << whole.num_tets()
          << " tets, " << mesh.num_triangles() << " of " << whole.num_triangles() << " triangles";
    } catch (const InputError&) {
      ++rejected;
    }
  }
  return rejected;
}

/// The message of the InputError `f` throws; fails the test (returning "") if it throws
/// nothing or something else.
inline std::string InputErrorMessage(const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  } catch (const std::exception& e) {
    ADD_FAILURE() << "expected InputError, got another exception: " << e.what();
    return "";
  }
  ADD_FAILURE() << "expected InputError, nothing was thrown";
  return "";
}

/// Appends the bytes of `value` (host order), reversed if `swap`.
template <class T>
void Put(std::string& out, T value, bool swap = false) {
  char bytes[sizeof(T)];
  std::memcpy(bytes, &value, sizeof(T));
  if (swap)
    for (std::size_t i = 0; i < sizeof(T) / 2; ++i) std::swap(bytes[i], bytes[sizeof(T) - 1 - i]);
  out.append(bytes, sizeof(T));
}

/// True on little-endian hosts.
inline bool LittleEndianHost() {
  std::uint16_t one = 1;
  char first = 0;
  std::memcpy(&first, &one, 1);
  return first == 1;
}

/// `a` and `b` are the same block of a mesh (every field of MeshBlock); `what` names the case.
inline void ExpectSameBlock(const MeshBlock& a, const MeshBlock& b, const std::string& what) {
  EXPECT_EQ(a.rank, b.rank) << what;
  EXPECT_EQ(a.size, b.size) << what;
  EXPECT_EQ(a.num_nodes, b.num_nodes) << what;
  EXPECT_EQ(a.num_tets, b.num_tets) << what;
  EXPECT_EQ(a.num_triangles, b.num_triangles) << what;
  EXPECT_EQ(a.first_triangle, b.first_triangle) << what;
  EXPECT_EQ(a.nodes, b.nodes) << what;
  EXPECT_EQ(a.tets, b.tets) << what;
  EXPECT_EQ(a.triangles, b.triangles) << what;
  EXPECT_EQ(a.tet_ids, b.tet_ids) << what;
  EXPECT_EQ(a.tet_id_kind, b.tet_id_kind) << what;
  ASSERT_EQ(a.groups.size(), b.groups.size()) << what;
  for (std::size_t g = 0; g < a.groups.size(); ++g) {
    EXPECT_EQ(a.groups[g].name, b.groups[g].name) << what;
    EXPECT_EQ(a.groups[g].dim, b.groups[g].dim) << what << ", group " << a.groups[g].name;
    EXPECT_EQ(a.groups[g].items, b.groups[g].items) << what << ", group " << a.groups[g].name;
  }
}

}  // namespace gipsi::test
