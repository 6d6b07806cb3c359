#pragma once
/// @file
/// Helpers shared by the mesh I/O tests: paths of test inputs, per-test scratch files, byte
/// builders for binary formats, capturing InputError messages, and comparing mesh blocks.

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

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

/// A zlib stream made of "stored" (uncompressed) deflate blocks: valid input for any inflater,
/// written without zlib so that the tests do not share code with the readers.
inline std::string StoredZlib(std::string_view data) {
  std::string out = "\x78\x01";
  std::size_t pos = 0;
  do {
    auto n = static_cast<std::uint16_t>(std::min<std::size_t>(65535, data.size() - pos));
    out += static_cast<char>(pos + n == data.size() ? 1 : 0);
    Put<std::uint16_t>(out, n, !LittleEndianHost());
    Put<std::uint16_t>(out, static_cast<std::uint16_t>(~n), !LittleEndianHost());
    out.append(data.substr(pos, n));
    pos += n;
  } while (pos < data.size());
  std::uint32_t a = 1, b = 0;
  for (char c : data) {
    a = (a + static_cast<unsigned char>(c)) % 65521;
    b = (b + a) % 65521;
  }
  Put<std::uint32_t>(out, b << 16 | a, LittleEndianHost());  // big-endian
  return out;
}

/// A VTK cell: its type and points.
struct VtkCell {
  int type;
  std::vector<Index> points;
};

/// The box's tets and triangles as VTK cells, interleaved (a triangle after every third tet),
/// with a vertex first, a line and an empty polyvertex in the middle: cells the readers skip.
inline std::vector<VtkCell> BoxCells(const Mesh& box) {
  std::vector<VtkCell> cells = {{1, {0}}};
  Index triangle = 0;
  auto add_triangle = [&] {
    cells.push_back(
        {5, {box.triangles(0, triangle), box.triangles(1, triangle), box.triangles(2, triangle)}});
    ++triangle;
  };
  for (Index e = 0; e < box.num_tets(); ++e) {
    cells.push_back({10, {box.tets(0, e), box.tets(1, e), box.tets(2, e), box.tets(3, e)}});
    if (e % 3 == 2 && triangle < box.num_triangles()) add_triangle();
    if (e == box.num_tets() / 2) {
      cells.push_back({3, {0, 1}});
      cells.push_back({2, {}});
    }
  }
  while (triangle < box.num_triangles()) add_triangle();
  return cells;
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
