#include "gipsi/io/vtu_writer.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdint>
#include <cstring>
#include <initializer_list>
#include <utility>

#include <fmt/format.h>

#include "gipsi/base/error.h"
#include "gipsi/io/base64.h"
#include "gipsi/io/text_reader.h"

namespace gipsi {
namespace {

std::string EscapeXml(std::string_view s) {
  std::string out;
  for (char c : s) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

/// VTK's inline binary layout: base64(UInt64 byte count) followed by base64(bytes).
std::string EncodeBlock(const void* data, std::size_t bytes) {
  auto header = static_cast<std::uint64_t>(bytes);
  std::string out =
      internal::EncodeBase64(std::string_view(reinterpret_cast<const char*>(&header), 8));
  out += internal::EncodeBase64(std::string_view(static_cast<const char*>(data), bytes));
  return out;
}

/// The text of a data array around its encoded block (VtuFileBytes counts the same strings).
std::string ArrayOpening(std::string_view type, std::string_view name, int components) {
  std::string xml = fmt::format("        <DataArray type=\"{}\"", type);
  if (!name.empty()) xml += fmt::format(" Name=\"{}\"", EscapeXml(name));
  if (components != 1) xml += fmt::format(" NumberOfComponents=\"{}\"", components);
  xml += " format=\"binary\">\n          ";
  return xml;
}
constexpr std::string_view kArrayClosing = "\n        </DataArray>\n";

/// Length of base64 text for `bytes` bytes (padded to whole 4-character groups).
std::uintmax_t Base64Length(std::uintmax_t bytes) { return 4 * ((bytes + 2) / 3); }

/// Length of an array: opening, base64 of its UInt64 byte count and of its bytes, closing.
std::uintmax_t ArrayBytes(std::string_view type, std::string_view name, int components,
                          std::uintmax_t bytes) {
  return ArrayOpening(type, name, components).size() + Base64Length(8) + Base64Length(bytes) +
         kArrayClosing.size();
}

std::string PieceOpening(Index num_nodes, Index num_cells) {
  std::string xml = "<?xml version=\"1.0\"?>\n";
  xml += fmt::format(
      "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"{}\" "
      "header_type=\"UInt64\">\n  <UnstructuredGrid>\n"
      "    <Piece NumberOfPoints=\"{}\" NumberOfCells=\"{}\">\n",
      internal::HostIsLittleEndian() ? "LittleEndian" : "BigEndian", num_nodes, num_cells);
  return xml;
}
constexpr std::string_view kPointsOpening = "      <Points>\n";
constexpr std::string_view kCellsOpening = "      </Points>\n      <Cells>\n";
constexpr std::string_view kPieceClosing =
    "      </Cells>\n    </Piece>\n  </UnstructuredGrid>\n</VTKFile>\n";

void AppendArray(std::string& xml, std::string_view type, std::string_view name, int components,
                 const void* data, std::size_t bytes) {
  xml += ArrayOpening(type, name, components);
  xml += EncodeBlock(data, bytes);
  xml += kArrayClosing;
}

void AppendFields(std::string& xml, const char* tag, const std::vector<NamedArray>& arrays,
                  Index count) {
  xml += fmt::format("      <{}>\n", tag);
  for (const NamedArray& a : arrays) {
    GIPSI_CHECK(a.components >= 1 && a.values.rows() == a.components && a.values.cols() == count,
                "{} array '{}' is {} by {}, expected {} by {}", tag, a.name, a.values.rows(),
                a.values.cols(), a.components, count);
    AppendArray(xml, "Float64", a.name, a.components, a.values.data(),
                sizeof(double) * static_cast<std::size_t>(a.values.size()));
  }
  xml += fmt::format("      </{}>\n", tag);
}

/// Cells of one kind: `rows` node indices per cell, column-major, and their VTK type.
struct CellBlock {
  const int* data = nullptr;
  Index rows = 0;
  Index cols = 0;
  std::uint8_t type = 0;
};

void WriteCells(const std::filesystem::path& path, const Points& nodes,
                std::initializer_list<CellBlock> blocks, const VtuFields& fields) {
  const Index num_nodes = nodes.cols();
  Index num_cells = 0;
  std::size_t num_indices = 0;
  for (const CellBlock& b : blocks) {
    num_cells += b.cols;
    num_indices += static_cast<std::size_t>(b.rows * b.cols);
  }
  std::vector<std::int64_t> conn;
  std::vector<std::int64_t> offsets;
  std::vector<std::uint8_t> types;
  conn.reserve(num_indices);
  offsets.reserve(static_cast<std::size_t>(num_cells));
  types.reserve(static_cast<std::size_t>(num_cells));
  for (const CellBlock& b : blocks) {
    for (Index e = 0; e < b.cols; ++e) {
      for (Index a = 0; a < b.rows; ++a) {
        const int n = b.data[e * b.rows + a];
        GIPSI_CHECK(n >= 0 && n < num_nodes, "cell node index {} out of range [0, {})", n,
                    num_nodes);
        conn.push_back(n);
      }
      offsets.push_back(static_cast<std::int64_t>(conn.size()));
      types.push_back(b.type);
    }
  }
  std::string xml = PieceOpening(num_nodes, num_cells);
  AppendFields(xml, "PointData", fields.point_data, num_nodes);
  AppendFields(xml, "CellData", fields.cell_data, num_cells);
  xml += kPointsOpening;
  AppendArray(xml, "Float64", "Points", 3, nodes.data(),
              sizeof(double) * static_cast<std::size_t>(nodes.size()));
  xml += kCellsOpening;
  AppendArray(xml, "Int64", "connectivity", 1, conn.data(), sizeof(std::int64_t) * conn.size());
  AppendArray(xml, "Int64", "offsets", 1, offsets.data(), sizeof(std::int64_t) * offsets.size());
  AppendArray(xml, "UInt8", "types", 1, types.data(), types.size());
  xml += kPieceClosing;
  internal::WriteFileBytes(path, xml);
}

/// VtuFileBytes for `cells` cells of `indices` node indices in all.
std::uintmax_t FileBytes(Index num_nodes, Index num_cells, std::uintmax_t indices,
                         const std::vector<VtuArrayShape>& point_data,
                         const std::vector<VtuArrayShape>& cell_data) {
  const auto nodes = static_cast<std::uintmax_t>(num_nodes);
  const auto cells = static_cast<std::uintmax_t>(num_cells);
  std::uintmax_t total = PieceOpening(num_nodes, num_cells).size();
  auto fields = [&](std::string_view tag, const std::vector<VtuArrayShape>& arrays,
                    std::uintmax_t count) {
    total += fmt::format("      <{}>\n", tag).size() + fmt::format("      </{}>\n", tag).size();
    for (const VtuArrayShape& a : arrays)
      total += ArrayBytes("Float64", a.name, a.components,
                          8 * static_cast<std::uintmax_t>(a.components) * count);
  };
  fields("PointData", point_data, nodes);
  fields("CellData", cell_data, cells);
  total += kPointsOpening.size() + ArrayBytes("Float64", "Points", 3, 24 * nodes);
  total += kCellsOpening.size() + ArrayBytes("Int64", "connectivity", 1, 8 * indices) +
           ArrayBytes("Int64", "offsets", 1, 8 * cells) + ArrayBytes("UInt8", "types", 1, cells);
  return total + kPieceClosing.size();
}

}  // namespace

void WriteVtu(const std::filesystem::path& path, const Points& nodes, const Tets& tets,
              const Triangles& triangles, const VtuFields& fields) {
  WriteCells(path, nodes,
             {{tets.data(), 4, tets.cols(), 10}, {triangles.data(), 3, triangles.cols(), 5}},
             fields);
}

void WriteQuadraticVtu(const std::filesystem::path& path, const Points& nodes,
                       const QuadraticTetCells& tets, const VtuFields& fields) {
  WriteCells(path, nodes, {{tets.data(), 10, tets.cols(), 24}}, fields);
}

std::uintmax_t QuadraticVtuFileBytes(Index num_nodes, Index num_tets,
                                     const std::vector<VtuArrayShape>& point_data,
                                     const std::vector<VtuArrayShape>& cell_data) {
  return FileBytes(num_nodes, num_tets, 10 * static_cast<std::uintmax_t>(num_tets), point_data,
                   cell_data);
}

std::uintmax_t VtuFileBytes(Index num_nodes, Index num_tets, Index num_triangles,
                            const std::vector<VtuArrayShape>& point_data,
                            const std::vector<VtuArrayShape>& cell_data) {
  return FileBytes(num_nodes, num_tets + num_triangles,
                   static_cast<std::uintmax_t>(4 * num_tets + 3 * num_triangles), point_data,
                   cell_data);
}

void WritePvtu(const std::filesystem::path& path, const std::vector<std::string>& pieces,
               const std::vector<VtuArrayShape>& point_data,
               const std::vector<VtuArrayShape>& cell_data) {
  std::string xml = "<?xml version=\"1.0\"?>\n";
  xml += fmt::format(
      "<VTKFile type=\"PUnstructuredGrid\" version=\"1.0\" byte_order=\"{}\" "
      "header_type=\"UInt64\">\n  <PUnstructuredGrid GhostLevel=\"0\">\n",
      internal::HostIsLittleEndian() ? "LittleEndian" : "BigEndian");
  auto arrays = [&](std::string_view tag, const std::vector<VtuArrayShape>& shapes) {
    xml += fmt::format("    <{}>\n", tag);
    for (const VtuArrayShape& a : shapes)
      xml += fmt::format(
          "      <PDataArray type=\"Float64\" Name=\"{}\" NumberOfComponents=\"{}\"/>\n",
          EscapeXml(a.name), a.components);
    xml += fmt::format("    </{}>\n", tag);
  };
  arrays("PPointData", point_data);
  arrays("PCellData", cell_data);
  xml +=
      "    <PPoints>\n      <PDataArray type=\"Float64\" NumberOfComponents=\"3\"/>\n"
      "    </PPoints>\n";
  for (const std::string& piece : pieces)
    xml += fmt::format("    <Piece Source=\"{}\"/>\n", EscapeXml(piece));
  xml += "  </PUnstructuredGrid>\n</VTKFile>\n";
  internal::WriteFileBytes(path, xml);
}

void WriteVtu(const std::filesystem::path& path, const Mesh& mesh, const VtuFields& fields) {
  WriteVtu(path, mesh.nodes, mesh.tets, mesh.triangles, fields);
}

PvdWriter::PvdWriter(std::filesystem::path path, bool write) : path_(std::move(path)) {
  if (write) Rewrite();
}

void PvdWriter::AddFrame(double time, const std::string& file) {
  frames_.push_back({time, file});
  if (!Append()) Rewrite();
}

namespace {

constexpr std::string_view kPvdClosing = "  </Collection>\n</VTKFile>\n";

std::string PvdDataSet(double time, const std::string& file) {
  return fmt::format("    <DataSet timestep=\"{}\" group=\"\" part=\"0\" file=\"{}\"/>\n", time,
                     EscapeXml(file));
}

/// Writes all of `bytes` at `offset`; false if the file took fewer.
bool WriteAllAt(int fd, std::string_view bytes, std::uintmax_t offset) {
  while (!bytes.empty()) {
    const ssize_t n = ::pwrite(fd, bytes.data(), bytes.size(), static_cast<off_t>(offset));
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    bytes.remove_prefix(static_cast<std::size_t>(n));
    offset += static_cast<std::uintmax_t>(n);
  }
  return true;
}

}  // namespace

void PvdWriter::Rewrite() {
  written_ = false;
  std::string xml = "<?xml version=\"1.0\"?>\n";
  xml += fmt::format("<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"{}\">\n",
                     internal::HostIsLittleEndian() ? "LittleEndian" : "BigEndian");
  xml += "  <Collection>\n";
  for (const Frame& f : frames_) xml += PvdDataSet(f.time, f.file);
  tail_ = xml.size();
  xml += kPvdClosing;
  internal::WriteFileAtomically(path_, xml);
  written_ = true;
}

bool PvdWriter::Append() {
  if (!written_) return false;
  const int fd = ::open(path_.c_str(), O_WRONLY | O_CLOEXEC);
  if (fd < 0) return false;
  struct stat info {};
  bool ok = ::fstat(fd, &info) == 0 &&
            static_cast<std::uintmax_t>(info.st_size) == tail_ + kPvdClosing.size();
  if (ok) {
    const std::string line = PvdDataSet(frames_.back().time, frames_.back().file);
    ok = WriteAllAt(fd, line + std::string(kPvdClosing), tail_);
    if (ok) {
      tail_ += line.size();
    } else {  // a short write (e.g. a full disk): put the old end back before rewriting whole
      WriteAllAt(fd, kPvdClosing, tail_);
      [[maybe_unused]] const int r =
          ::ftruncate(fd, static_cast<off_t>(tail_ + kPvdClosing.size()));
    }
  }
  ::close(fd);
  if (!ok) written_ = false;
  return ok;
}

}  // namespace gipsi
