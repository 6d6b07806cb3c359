#include "gipsi/io/vtu_writer.h"

#include <sys/resource.h>

#include <csignal>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <fmt/format.h>

#include "gipsi/base/file_io.h"
#include "gipsi/io/base64.h"
#include "gipsi/io/gmsh_reader.h"
#include "gipsi/io/vtu_reader.h"
#include "io/io_test_util.h"

namespace gipsi {
namespace {

using test::Scratch;
using ::testing::HasSubstr;
using ::testing::Not;

/// The liver tet mesh with a few boundary-like triangles and irrational coordinates.
Mesh MixedMesh() {
  Mesh mesh = ReadGmsh(test::SharedData("liver/liver.msh"));
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> noise(-1e-3, 1e-3);
  for (Index i = 0; i < mesh.num_nodes(); ++i)
    for (int k = 0; k < 3; ++k) mesh.nodes(k, i) += noise(rng) / 3.0;
  mesh.triangles.resize(3, 5);
  for (Index t = 0; t < 5; ++t) mesh.triangles.col(t) = mesh.tets.col(10 * t).head<3>();
  return mesh;
}

TEST(VtuWriter, RoundTripsMixedTetsAndTrianglesExactly) {
  Mesh mesh = MixedMesh();
  auto path = Scratch("mixed.vtu");
  WriteVtu(path, mesh);
  Mesh back = ReadVtu(path);
  ASSERT_EQ(back.num_nodes(), mesh.num_nodes());
  EXPECT_LE((back.nodes - mesh.nodes).cwiseAbs().maxCoeff(), 1e-15);
  EXPECT_EQ(back.tets, mesh.tets);
  EXPECT_EQ(back.triangles, mesh.triangles);
}

TEST(VtuWriter, WritesPointAndCellDataBitExactly) {
  Mesh mesh = MixedMesh();
  VtuFields fields;
  fields.point_data.push_back({"displacement", 3, Eigen::MatrixXd::Random(3, mesh.num_nodes())});
  fields.cell_data.push_back({"stress <von Mises>", 1,
                              Eigen::MatrixXd::Random(1, mesh.num_tets() + mesh.num_triangles())});
  auto path = Scratch("fields.vtu");
  WriteVtu(path, mesh.nodes, mesh.tets, mesh.triangles, fields);
  std::string xml = test::ReadBytes(path);
  EXPECT_THAT(xml, HasSubstr(R"(Name="displacement" NumberOfComponents="3" format="binary">)"));
  EXPECT_THAT(xml, HasSubstr(R"(Name="stress &lt;von Mises&gt;" format="binary">)"));
  // Decode the displacement array: UInt64 byte count, then the doubles.
  std::size_t begin = xml.find('>', xml.find("Name=\"displacement\"")) + 1;
  std::size_t end = xml.find("</DataArray>", begin);
  auto bytes = internal::DecodeBase64(std::string_view(xml).substr(begin, end - begin));
  ASSERT_TRUE(bytes.has_value());
  const auto& values = fields.point_data[0].values;
  std::uint64_t count = 0;
  std::memcpy(&count, bytes->data(), 8);
  ASSERT_EQ(count, sizeof(double) * std::size_t(values.size()));
  ASSERT_EQ(bytes->size(), 8 + count);
  EXPECT_EQ(std::memcmp(bytes->data() + 8, values.data(), count), 0);
  EXPECT_EQ(ReadVtu(path).num_tets(), mesh.num_tets());  // still a readable grid
}

// Quadratic tets (VTK type 24) read back as linear tets on their corners with the middle
// points as the mesh's second-order geometry, bit for bit; the file's size is predicted.
TEST(VtuWriter, RoundTripsQuadraticTetsThroughTheSecondOrderGeometry) {
  const Mesh order2 = ReadGmsh(test::MeshData("two_tets_order2_v22.msh"));
  // Nodes: the corners, then one per edge (VTK's edge order, the middle nodes of the file).
  const int edges[6][2] = {{0, 1}, {1, 2}, {0, 2}, {0, 3}, {1, 3}, {2, 3}};
  Points nodes(3, order2.num_nodes() + order2.edge_nodes.cols());
  nodes << order2.nodes, order2.edge_nodes;
  QuadraticTetCells cells(10, order2.num_tets());
  for (Index e = 0; e < order2.num_tets(); ++e) {
    cells.col(e).head<4>() = order2.tets.col(e);
    for (int k = 0; k < 6; ++k) {
      const int a = std::min(order2.tets(edges[k][0], e), order2.tets(edges[k][1], e));
      const int b = std::max(order2.tets(edges[k][0], e), order2.tets(edges[k][1], e));
      for (Index j = 0; j < order2.edge_node_ends.cols(); ++j)
        if (order2.edge_node_ends(0, j) == a && order2.edge_node_ends(1, j) == b)
          cells(4 + k, e) = static_cast<int>(order2.num_nodes() + j);
    }
  }
  VtuFields fields;
  fields.point_data.push_back({"displacement", 3, Eigen::MatrixXd::Random(3, nodes.cols())});
  fields.cell_data.push_back({"volume_ratio", 1, Eigen::MatrixXd::Random(1, cells.cols())});
  auto path = Scratch("quadratic.vtu");
  WriteQuadraticVtu(path, nodes, cells, fields);
  EXPECT_EQ(QuadraticVtuFileBytes(nodes.cols(), cells.cols(), {{"displacement", 3}},
                                  {{"volume_ratio", 1}}),
            std::filesystem::file_size(path));
  const Mesh back = ReadVtu(path);
  EXPECT_EQ(back.nodes, order2.nodes);
  EXPECT_EQ(back.tets, order2.tets);
  EXPECT_EQ(back.edge_node_ends, order2.edge_node_ends);
  EXPECT_EQ(back.edge_nodes, order2.edge_nodes);
}

// Two quadratic tets on one edge with different middle points: the reader names both.
TEST(VtuWriter, QuadraticTetsThatDisagreeOnAnEdgeAreRefusedWhenRead) {
  Points nodes(3, 17);
  nodes.leftCols<5>() << 0, 1, 0, 0, 1, 0, 0, 1, 0, 1, 0, 0, 0, 1, 1;
  nodes.rightCols<12>().setRandom();
  QuadraticTetCells cells(10, 2);
  cells.col(0) << 0, 1, 2, 3, 5, 6, 7, 8, 9, 10;
  cells.col(1) << 1, 2, 3, 4, 16, 11, 12, 13, 14, 15;  // edge (1, 2): point 16, not 6
  auto path = Scratch("nonconforming.vtu");
  WriteQuadraticVtu(path, nodes, cells);
  EXPECT_THAT(test::InputErrorMessage([&] { ReadVtu(path); }),
              HasSubstr("cell 1 puts point 16 in the middle of an edge where another cell has "
                        "point 6: the quadratic cells do not conform"));
}

TEST(VtuWriter, RejectsUnwritablePathNamingTheReason) {
  try {
    WriteVtu("/nonexistent/dir/x.vtu", Mesh{});
    ADD_FAILURE() << "no error";
  } catch (const OutputError& e) {
    EXPECT_EQ(std::string(e.what()),
              "/nonexistent/dir/x.vtu: cannot create the file: No such file or directory");
  }
}

TEST(VtuWriter, AFailedWriteLeavesNeitherAPartialFileNorItsTemporary) {
  // A frame that does not fit (here: over the process's file size limit, as on a full disk)
  // fails with the system's reason and leaves the old file whole.
  const auto path = test::Scratch("limited.vtu");
  std::filesystem::remove(path);
  Mesh mesh;
  mesh.nodes = Points::Random(3, 5000);
  WriteVtu(path, Mesh{});
  const auto old_size = std::filesystem::file_size(path);
  rlimit old_limit{};
  ASSERT_EQ(getrlimit(RLIMIT_FSIZE, &old_limit), 0);
  std::signal(SIGXFSZ, SIG_IGN);  // the write fails with EFBIG instead of killing the process
  rlimit limit = old_limit;
  limit.rlim_cur = 4096;
  ASSERT_EQ(setrlimit(RLIMIT_FSIZE, &limit), 0);
  std::string message;
  try {
    WriteVtu(path, mesh);
  } catch (const OutputError& e) {
    message = e.what();
  }
  ASSERT_EQ(setrlimit(RLIMIT_FSIZE, &old_limit), 0);
  std::signal(SIGXFSZ, SIG_DFL);
  EXPECT_EQ(message, path.string() + ": cannot write: File too large");
  EXPECT_EQ(std::filesystem::file_size(path), old_size);
  EXPECT_FALSE(std::filesystem::exists(path.string() + ".tmp"));
}

TEST(VtuWriter, Base64RoundTripsEveryLengthAndSplitPadding) {
  std::string data;
  for (int n = 0; n < 40; ++n) {
    auto decoded = internal::DecodeBase64(internal::EncodeBase64(data));
    ASSERT_TRUE(decoded.has_value());
    EXPECT_EQ(*decoded, data);
    // Two separately padded encodings decode to the concatenation.
    auto joined =
        internal::DecodeBase64(internal::EncodeBase64(data) + "\n" + internal::EncodeBase64("xy"));
    ASSERT_TRUE(joined.has_value());
    EXPECT_EQ(*joined, data + "xy");
    data += static_cast<char>(n * 37);
  }
  EXPECT_FALSE(internal::DecodeBase64("QUJD*").has_value());
}

TEST(PvdWriter, KeepsAValidCollectionAfterEveryFrame) {
  auto path = Scratch("run.pvd");
  PvdWriter pvd(path);
  EXPECT_THAT(test::ReadBytes(path), HasSubstr("<Collection>\n  </Collection>"));
  pvd.AddFrame(0.0, "run_0000.vtu");
  pvd.AddFrame(0.125, "run_0001.vtu");
  std::string xml = test::ReadBytes(path);
  EXPECT_THAT(xml, HasSubstr(R"(<DataSet timestep="0" group="" part="0" file="run_0000.vtu"/>)"));
  EXPECT_THAT(xml,
              HasSubstr(R"(<DataSet timestep="0.125" group="" part="0" file="run_0001.vtu"/>)"));
  EXPECT_THAT(xml, HasSubstr("</VTKFile>"));
  EXPECT_EQ(pvd.num_frames(), 2u);
  EXPECT_FALSE(std::filesystem::exists(path.string() + ".tmp"));
}

TEST(PvdWriter, FramesWrittenInPlaceGiveTheSameFileAsAWholeRewrite) {
  // Each frame after the first write goes over the closing tags; the result must be the file a
  // whole rewrite of the same frames gives, byte for byte, after every frame.
  auto path = Scratch("appended.pvd");
  auto whole = Scratch("whole.pvd");
  PvdWriter pvd(path);
  // A second name for the file: writes in place show through it, a rewrite (a new file renamed
  // over the old name) would leave it behind.
  const auto link = Scratch("link.pvd");
  std::filesystem::create_hard_link(path, link);
  std::vector<std::pair<double, std::string>> frames;
  for (int i = 0; i < 40; ++i) {
    frames.emplace_back(0.1 * i, fmt::format("run/run_{:06d}.vtu", i));
    pvd.AddFrame(frames.back().first, frames.back().second);
    PvdWriter reference(whole, false);
    reference.SetFrames(frames);
    ASSERT_EQ(test::ReadBytes(path), test::ReadBytes(whole)) << "after frame " << i;
    ASSERT_EQ(test::ReadBytes(link), test::ReadBytes(path)) << "rewritten at frame " << i;
  }
  // A file name with XML metacharacters is escaped in place as in a rewrite.
  frames.emplace_back(4.0, "a&b<c>\"d\".vtu");
  pvd.AddFrame(frames.back().first, frames.back().second);
  PvdWriter reference(whole, false);
  reference.SetFrames(frames);
  EXPECT_EQ(test::ReadBytes(path), test::ReadBytes(whole));
  EXPECT_THAT(test::ReadBytes(path), HasSubstr("a&amp;b&lt;c&gt;&quot;d&quot;.vtu"));
}

TEST(PvdWriter, AFileChangedBehindItsBackIsWrittenWhole) {
  auto path = Scratch("changed.pvd");
  PvdWriter pvd(path);
  pvd.AddFrame(0.0, "f0.vtu");
  pvd.AddFrame(1.0, "f1.vtu");
  std::ofstream(path, std::ios::trunc) << "something else";  // another program's doing
  pvd.AddFrame(2.0, "f2.vtu");
  std::string xml = test::ReadBytes(path);
  for (const char* f : {"f0.vtu", "f1.vtu", "f2.vtu"}) EXPECT_THAT(xml, HasSubstr(f));
  EXPECT_THAT(xml, HasSubstr("</VTKFile>\n"));
  EXPECT_THAT(xml, Not(HasSubstr("something else")));
  std::filesystem::remove(path);
  pvd.AddFrame(3.0, "f3.vtu");
  xml = test::ReadBytes(path);
  for (const char* f : {"f0.vtu", "f1.vtu", "f2.vtu", "f3.vtu"}) EXPECT_THAT(xml, HasSubstr(f));
  pvd.AddFrame(4.0, "f4.vtu");  // in place again
  PvdWriter reference(Scratch("changed_whole.pvd"), false);
  reference.SetFrames(
      {{0.0, "f0.vtu"}, {1.0, "f1.vtu"}, {2.0, "f2.vtu"}, {3.0, "f3.vtu"}, {4.0, "f4.vtu"}});
  EXPECT_EQ(test::ReadBytes(path), test::ReadBytes(Scratch("changed_whole.pvd")));
}

}  // namespace
}  // namespace gipsi
