// Reading one block of a VTK XML unstructured grid without the whole mesh (ReadVtuBlock),
// against the whole-file reader's mesh sliced into the same block, for every array layout the
// whole reader reads; files it leaves to the whole reader, and mistakes named as that names them.

#include "gipsi/io/vtu_block_reader.h"

#include <algorithm>
#include <cstdint>
#include <functional>
#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

#include <fmt/format.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "gipsi/base/error.h"
#include "gipsi/geometry/generators.h"
#include "gipsi/io/base64.h"
#include "gipsi/io/vtu_reader.h"
#include "io/io_test_util.h"

namespace gipsi {
namespace {

using test::BoxCells;
using test::InputErrorMessage;
using test::Put;
using test::Scratch;
using test::StoredZlib;
using test::VtkCell;
using test::WriteBytes;
using ::testing::HasSubstr;

/// How a file's arrays are stored: every form ReadVtu reads.
enum class Layout {
  kAscii,                 // format="ascii"
  kInline,                // format="binary", header and data base64-encoded together
  kInlineSeparateHeader,  // format="binary", header and data encoded separately (VTK, GiPSi)
  kInlineZlib,            // format="binary", zlib-compressed, encoded separately
  kAppendedRaw,           // <AppendedData encoding="raw">
  kAppendedRawZlib,       // raw, zlib-compressed
  kAppendedBase64,        // <AppendedData encoding="base64">, header and data encoded together
  kAppendedBase64Zlib,    // base64, zlib-compressed, header and data encoded separately
};

constexpr Layout kLayouts[] = {Layout::kAscii,
                               Layout::kInline,
                               Layout::kInlineSeparateHeader,
                               Layout::kInlineZlib,
                               Layout::kAppendedRaw,
                               Layout::kAppendedRawZlib,
                               Layout::kAppendedBase64,
                               Layout::kAppendedBase64Zlib};

const char* Name(Layout layout) {
  switch (layout) {
    case Layout::kAscii:
      return "ascii";
    case Layout::kInline:
      return "inline";
    case Layout::kInlineSeparateHeader:
      return "inline_separate_header";
    case Layout::kInlineZlib:
      return "inline_zlib";
    case Layout::kAppendedRaw:
      return "appended_raw";
    case Layout::kAppendedRawZlib:
      return "appended_raw_zlib";
    case Layout::kAppendedBase64:
      return "appended_base64";
    case Layout::kAppendedBase64Zlib:
      return "appended_base64_zlib";
  }
  return "?";
}

bool Compressed(Layout layout) {
  return layout == Layout::kInlineZlib || layout == Layout::kAppendedRawZlib ||
         layout == Layout::kAppendedBase64Zlib;
}

bool Appended(Layout layout) {
  return layout == Layout::kAppendedRaw || layout == Layout::kAppendedRawZlib ||
         layout == Layout::kAppendedBase64 || layout == Layout::kAppendedBase64Zlib;
}

/// A file's layout, header type and byte order; the array types follow from them, so that the
/// variants between them write every type the readers take for each array.
struct Variant {
  Layout layout = Layout::kAscii;
  bool header64 = false;
  bool big_endian = false;

  [[nodiscard]] int Number() const { return static_cast<int>(layout); }
  [[nodiscard]] bool PointsFloat32() const { return (Number() + int{header64}) % 2 == 1; }
  [[nodiscard]] bool ConnectivityInt64() const { return (Number() + int{big_endian}) % 2 == 0; }
  [[nodiscard]] bool OffsetsInt64() const {
    return (Number() + int{header64} + int{big_endian}) % 2 == 1;
  }
  [[nodiscard]] const char* PointsType() const { return PointsFloat32() ? "Float32" : "Float64"; }
  [[nodiscard]] const char* ConnectivityType() const {
    return ConnectivityInt64() ? "Int64" : "Int32";
  }
  [[nodiscard]] std::string Describe() const {
    return fmt::format("{}, UInt{} header, {}", Name(layout), header64 ? 64 : 32,
                       big_endian ? "BigEndian" : "LittleEndian");
  }
  [[nodiscard]] std::string FileName() const {
    return fmt::format("box_{}_{}_{}.vtu", Name(layout), header64 ? 64 : 32,
                       big_endian ? "be" : "le");
  }
};

std::vector<Variant> AllVariants() {
  std::vector<Variant> out;
  for (Layout layout : kLayouts)
    for (bool header64 : {false, true})
      for (bool big_endian : {false, true}) out.push_back({layout, header64, big_endian});
  return out;
}

/// Writes the <DataArray> elements of one file, collecting appended data.
class ArrayWriter {
 public:
  ArrayWriter(Layout layout, bool header64, bool big_endian)
      : layout_(layout), header64_(header64), swap_(big_endian == test::LittleEndianHost()) {}

  /// A <DataArray Name=`name`> of `values` stored as T (VTK type `type`), with `attributes`
  /// after the type and `inside` (markup) before the data.
  template <class T, class V>
  std::string Array(const std::string& name, const char* type, const std::vector<V>& values,
                    const std::string& attributes = "", const std::string& inside = "") {
    const std::string open =
        fmt::format(R"(<DataArray Name="{}" type="{}"{})", name, type, attributes);
    if (layout_ == Layout::kAscii) {
      std::string text = "\n          ";
      for (std::size_t i = 0; i < values.size(); ++i) {
        if constexpr (std::is_floating_point_v<T>)
          text += fmt::format("{}", static_cast<T>(values[i]));
        else
          text += std::to_string(static_cast<long long>(values[i]));
        text += i % 10 == 9 ? "\n          " : " ";
      }
      return open + R"( format="ascii">)" + inside + text + "\n        </DataArray>";
    }
    std::string payload;
    for (const V& v : values) Put(payload, static_cast<T>(v), swap_);
    const std::string block = Encode(payload);
    if (!Appended(layout_))
      return open + R"( format="binary">)" + inside + "\n          " + block +
             "\n        </DataArray>";
    std::string element = open + fmt::format(R"( format="appended" offset="{}")", appended_.size());
    appended_ += block;
    return inside.empty() ? element + "/>" : element + ">" + inside + "</DataArray>";
  }

  [[nodiscard]] const std::string& appended() const { return appended_; }

 private:
  void PutHeader(std::string& out, std::uint64_t v) const {
    if (header64_)
      Put<std::uint64_t>(out, v, swap_);
    else
      Put<std::uint32_t>(out, static_cast<std::uint32_t>(v), swap_);
  }

  /// The binary block (header and data) of `payload` as VTK lays it out, base64-encoded but for
  /// appended raw data.
  std::string Encode(std::string_view payload) const {
    std::string header, data;
    if (!Compressed(layout_)) {
      PutHeader(header, payload.size());
      data = payload;
    } else {
      // Small blocks, of sizes that 8-byte values straddle: arrays span many blocks.
      const std::size_t size = layout_ == Layout::kInlineZlib        ? 44
                               : layout_ == Layout::kAppendedRawZlib ? 64
                                                                     : 37;
      std::vector<std::string> blocks;
      for (std::size_t p = 0; p < payload.size(); p += size)
        blocks.push_back(StoredZlib(payload.substr(p, size)));
      PutHeader(header, blocks.size());
      PutHeader(header, size);
      PutHeader(header, payload.size() % size);
      for (const auto& b : blocks) {
        PutHeader(header, b.size());
        data += b;
      }
    }
    switch (layout_) {
      case Layout::kInline:
      case Layout::kAppendedBase64:
        return internal::EncodeBase64(header + data);
      case Layout::kAppendedRaw:
      case Layout::kAppendedRawZlib:
        return header + data;
      default:
        return internal::EncodeBase64(header) + internal::EncodeBase64(data);
    }
  }

  Layout layout_;
  bool header64_;
  bool swap_;
  std::string appended_;
};

/// The layout of the inline arrays of a file whose arrays are otherwise appended.
Layout InlineLayout(Layout layout) {
  if (!Appended(layout)) return layout;
  return Compressed(layout) ? Layout::kInlineZlib : Layout::kInline;
}

const char* const kInformationKey =
    "\n          <InformationKey name=\"L2_NORM_RANGE\" location=\"vtkDataArray\" length=\"2\">"
    "\n            <Value index=\"0\">\n              0\n            </Value>"
    "\n            <Value index=\"1\">\n              1\n            </Value>"
    "\n          </InformationKey>";

/// `nodes` and `cells` as a .vtu file of one <Piece>, in the variant's layout, with point data,
/// cell data, an InformationKey in the points' array and XML comments, which the readers skip.
std::string CellsAsVtu(const Points& nodes, const std::vector<VtkCell>& cells, const Variant& v) {
  ArrayWriter arrays(v.layout, v.header64, v.big_endian);
  ArrayWriter inline_arrays(InlineLayout(v.layout), v.header64, v.big_endian);
  std::vector<std::int64_t> offsets, connectivity, types;
  for (const VtkCell& cell : cells) {
    connectivity.insert(connectivity.end(), cell.points.begin(), cell.points.end());
    offsets.push_back(static_cast<std::int64_t>(connectivity.size()));
    types.push_back(cell.type);
  }
  std::vector<double> coords(nodes.data(), nodes.data() + nodes.size());
  std::vector<double> x;
  for (Index i = 0; i < nodes.cols(); ++i) x.push_back(nodes(0, i));

  std::string s = "<?xml version=\"1.0\"?>\n<!-- a box of tets by the GiPSi tests -->\n";
  s += fmt::format(R"(<VTKFile type="UnstructuredGrid" version="1.0" byte_order="{}")",
                   v.big_endian ? "BigEndian" : "LittleEndian");
  s += fmt::format(R"( header_type="{}")", v.header64 ? "UInt64" : "UInt32");
  if (Compressed(v.layout)) s += R"( compressor="vtkZLibDataCompressor")";
  s += ">\n  <UnstructuredGrid>\n";
  s += fmt::format("    <Piece NumberOfPoints=\"{}\" NumberOfCells=\"{}\">\n", nodes.cols(),
                   cells.size());
  s += "      <PointData Scalars=\"x\">\n        ";
  s += inline_arrays.Array<double>("x", "Float64", x);
  s += "\n      </PointData>\n      <CellData Scalars=\"kind\">\n        ";
  s += arrays.Array<std::int32_t>("kind", "Int32", types);
  s += "\n      </CellData>\n      <Points>\n        ";
  const std::string components = R"( NumberOfComponents="3")";
  s += v.PointsFloat32()
           ? arrays.Array<float>("Points", "Float32", coords, components, kInformationKey)
           : arrays.Array<double>("Points", "Float64", coords, components, kInformationKey);
  s += "\n      </Points>\n      <Cells>\n        <!-- connectivity, offsets, types -->\n        ";
  s += v.ConnectivityInt64() ? arrays.Array<std::int64_t>("connectivity", "Int64", connectivity)
                             : arrays.Array<std::int32_t>("connectivity", "Int32", connectivity);
  s += "\n        ";
  s += v.OffsetsInt64() ? arrays.Array<std::int64_t>("offsets", "Int64", offsets)
                        : arrays.Array<std::int32_t>("offsets", "Int32", offsets);
  s += "\n        ";
  s += arrays.Array<std::uint8_t>("types", "UInt8", types);
  s += "\n      </Cells>\n    </Piece>\n  </UnstructuredGrid>\n";
  if (Appended(v.layout)) {
    const bool raw = v.layout == Layout::kAppendedRaw || v.layout == Layout::kAppendedRawZlib;
    s += fmt::format("  <AppendedData encoding=\"{}\">\n   _", raw ? "raw" : "base64");
    s += arrays.appended() + "\n  </AppendedData>\n";
  }
  s += "</VTKFile>\n";
  return s;
}

/// A mesh made by MakeTetBox as a .vtu file (see CellsAsVtu), its tets and triangles
/// interleaved as BoxCells does.
std::string BoxAsVtu(const Mesh& box, Layout layout, bool header64, bool big_endian) {
  return CellsAsVtu(box.nodes, BoxCells(box), {layout, header64, big_endian});
}

std::string BoxAsVtu(const Mesh& box, const Variant& v) {
  return BoxAsVtu(box, v.layout, v.header64, v.big_endian);
}

/// A 4x2x2-cell box of spacing 0.5, whose coordinates Float32 holds exactly.
Mesh Box() { return MakeTetBox(Vec3::Zero(), Vec3(2, 1, 1), {4, 2, 2}); }

// The generated files are the box to the whole reader, in every layout, header type and byte
// order: its nodes, tets and triangles in the order written.
TEST(VtuBlockReader, TheGeneratedFilesAreTheBoxToTheWholeReader) {
  const Mesh box = Box();
  ASSERT_GT(box.num_tets(), 50);
  ASSERT_GT(box.num_triangles(), 50);
  for (const Variant& v : AllVariants()) {
    const Mesh mesh = ReadVtu(WriteBytes(Scratch(v.FileName()), BoxAsVtu(box, v)));
    ASSERT_EQ(mesh.num_nodes(), box.num_nodes()) << v.Describe();
    ASSERT_EQ(mesh.num_tets(), box.num_tets()) << v.Describe();
    ASSERT_EQ(mesh.num_triangles(), box.num_triangles()) << v.Describe();
    EXPECT_EQ(mesh.nodes, box.nodes) << v.Describe();
    EXPECT_EQ(mesh.tets, box.tets) << v.Describe();
    EXPECT_EQ(mesh.triangles, box.triangles) << v.Describe();
  }
}

// Every block, on 1, 3 and 7 processes, of the box in every layout, header type and byte order
// is the whole reader's mesh sliced into that block.
TEST(VtuBlockReader, EveryBlockIsTheWholeReadersSlice) {
  const Mesh box = Box();
  for (const Variant& v : AllVariants()) {
    const auto path = WriteBytes(Scratch(v.FileName()), BoxAsVtu(box, v));
    const Mesh whole = ReadVtu(path);
    for (int size : {1, 3, 7}) {
      for (int rank = 0; rank < size; ++rank) {
        const auto block = ReadVtuBlock(path, rank, size);
        ASSERT_TRUE(block.has_value()) << v.Describe();
        test::ExpectSameBlock(*block, BlockOfMesh(whole, rank, size),
                              fmt::format("{}, block {} of {}", v.Describe(), rank, size));
      }
    }
  }
}

/// `text` with the first `from` after the first `after` replaced by `to`; fails the test if
/// either is missing.
std::string Replaced(std::string text, std::string_view from, std::string_view to,
                     std::string_view after = "") {
  const std::size_t start = text.find(after);
  EXPECT_NE(start, std::string::npos) << after;
  const std::size_t at = start == std::string::npos ? start : text.find(from, start);
  EXPECT_NE(at, std::string::npos) << from << " after " << after;
  if (at != std::string::npos) text.replace(at, from.size(), to);
  return text;
}

// Files of several pieces, with quadratic cells or with a CDATA section, all of which the whole
// reader reads, are left to it.
TEST(VtuBlockReader, FilesItDoesNotReadInBlocksAreLeftToTheWholeReader) {
  const Mesh box = MakeTetBox(Vec3::Zero(), Vec3(1, 1, 1), {1, 2, 1});
  auto left_to_whole_reader = [](const std::string& name, const std::string& text) {
    const auto path = WriteBytes(Scratch(name), text);
    EXPECT_NO_THROW((void)ReadVtu(path)) << name;
    for (int size : {1, 2})
      for (int rank = 0; rank < size; ++rank)
        EXPECT_FALSE(ReadVtuBlock(path, rank, size).has_value()) << name << ", block " << rank;
  };
  for (Layout layout : {Layout::kAscii, Layout::kInlineZlib, Layout::kAppendedRaw}) {
    const std::string text = BoxAsVtu(box, layout, false, false);
    const std::size_t begin = text.find("    <Piece "), end = text.find("</Piece>\n") + 9;
    ASSERT_LT(begin, end);
    left_to_whole_reader(fmt::format("pieces_{}.vtu", Name(layout)),
                         text.substr(0, end) + text.substr(begin, end - begin) + text.substr(end));
  }
  // One quadratic tet (VTK type 24: its corners, then its edges' middle points) and a linear one.
  Points nodes(3, 11);
  nodes << 0, 2, 0, 0, 1, 1, 0, 0, 1, 0, 2,  //
      0, 0, 2, 0, 0, 1, 1, 0, 0, 1, 2,       //
      0, 0, 0, 2, 0, 0, 0, 1, 1, 1, 2;
  const std::vector<VtkCell> quadratic = {{24, {0, 1, 2, 3, 4, 5, 6, 7, 8, 9}},
                                          {10, {1, 2, 3, 10}}};
  for (Layout layout : {Layout::kAscii, Layout::kInlineSeparateHeader, Layout::kAppendedRawZlib})
    left_to_whole_reader(fmt::format("quadratic_tet_{}.vtu", Name(layout)),
                         CellsAsVtu(nodes, quadratic, {layout, true, false}));
  const std::vector<VtkCell> triangle = {{22, {0, 1, 2, 4, 5, 6}}, {10, {1, 2, 3, 10}}};
  left_to_whole_reader("quadratic_triangle.vtu", CellsAsVtu(nodes, triangle, {}));
  // Data in a CDATA section (the offsets, ascii; or the points, base64).
  const std::string ascii = BoxAsVtu(box, Layout::kAscii, false, false);
  std::string cdata =
      Replaced(ascii, R"(format="ascii">)", R"(format="ascii"><![CDATA[)", R"(Name="offsets")");
  left_to_whole_reader("cdata_ascii.vtu",
                       Replaced(cdata, "</DataArray>", "]]></DataArray>", R"(Name="offsets")"));
  const std::string binary = BoxAsVtu(box, Layout::kInline, false, false);
  cdata = Replaced(binary, "</InformationKey>", "</InformationKey><![CDATA[", R"(Name="Points")");
  left_to_whole_reader("cdata_binary.vtu",
                       Replaced(cdata, "</DataArray>", "]]></DataArray>", R"(Name="Points")"));
}

/// A broken file, what is wrong with it, and a part of the whole reader's message for it.
struct Mistake {
  std::string name;
  std::string text;
  std::string says;
};

/// `text` with the 4-byte or 8-byte header word at `at` set to `value`.
std::string WithHeaderWord(std::string text, std::size_t at, std::uint64_t value,
                           const Variant& v) {
  std::string word;
  const bool swap = v.big_endian == test::LittleEndianHost();
  if (v.header64)
    Put<std::uint64_t>(word, value, swap);
  else
    Put<std::uint32_t>(word, static_cast<std::uint32_t>(value), swap);
  text.replace(at, word.size(), word);
  return text;
}

/// `text` with the value at `at` set to `value`, in the variant's byte order.
template <class T>
std::string Patched(std::string text, std::size_t at, T value, const Variant& v) {
  std::string bytes;
  Put<T>(bytes, value, v.big_endian == test::LittleEndianHost());
  text.replace(at, bytes.size(), bytes);
  return text;
}

/// Where the inline data of array `name` starts in `text`.
std::size_t InlineStart(const std::string& text, const std::string& name) {
  return text.find(R"(format="binary">)", text.find("Name=\"" + name + "\"")) + 16 + 11;
}

/// `text` with the character at `at` set to `c`.
std::string WithChar(std::string text, std::size_t at, char c) {
  text[at] = c;
  return text;
}

/// Where the appended data of array `name` starts in `text`.
std::size_t AppendedStart(const std::string& text, const std::string& name) {
  const std::size_t element = text.find("Name=\"" + name + "\"");
  const std::size_t offset = text.find("offset=\"", element) + 8;
  const std::size_t data = text.find('_', text.find("<AppendedData")) + 1;
  return data + std::stoul(text.substr(offset, text.find('"', offset) - offset));
}

/// `text` with the base64 character at `at` changed.
std::string Flipped(std::string text, std::size_t at) {
  text[at] = text[at] == 'A' ? 'B' : 'A';
  return text;
}

/// `text` with the base64 character `back` characters before the end of array `name`'s
/// inline data changed.
std::string FlipBase64(const std::string& text, const std::string& name, std::size_t back) {
  return Flipped(text,
                 text.find("\n        </DataArray>", text.find("Name=\"" + name + "\"")) - back);
}

// Broken files, each with one mistake, and the same mistakes in data the block does not keep:
// the block reader names every one as the whole reader does, word for word, on every rank.
TEST(VtuBlockReader, MistakesAreNamedAsTheWholeReaderNamesThem) {
  const Mesh box = Box();
  const Variant ascii{Layout::kAscii, false, false};
  const Variant inline_le{Layout::kInline, false, false};
  const Variant separate_be{Layout::kInlineSeparateHeader, true, true};
  const Variant zlib_le{Layout::kInlineZlib, false, false};
  const Variant raw_le{Layout::kAppendedRaw, false, false};
  const Variant raw_zlib_be{Layout::kAppendedRawZlib, true, true};
  const Variant base64_le{Layout::kAppendedBase64, true, false};
  const Variant base64_zlib_be{Layout::kAppendedBase64Zlib, false, true};
  const std::string a = BoxAsVtu(box, ascii), i = BoxAsVtu(box, inline_le);
  const std::string s = BoxAsVtu(box, separate_be), z = BoxAsVtu(box, zlib_le);
  const std::string r = BoxAsVtu(box, raw_le), rz = BoxAsVtu(box, raw_zlib_be);
  const std::string b = BoxAsVtu(box, base64_le);
  const std::string end = "\n  </AppendedData>\n</VTKFile>\n";
  ASSERT_EQ(r.substr(r.size() - end.size()), end);

  Mesh nan = box, inf = box;
  nan.nodes(1, 3) = std::numeric_limits<double>::quiet_NaN();
  inf.nodes(2, 40) = -std::numeric_limits<double>::infinity();
  auto cells = [&](const std::function<void(std::vector<VtkCell>&)>& change, const Variant& v) {
    std::vector<VtkCell> c = BoxCells(box);
    change(c);
    return CellsAsVtu(box.nodes, c, v);
  };
  // The base64 characters of the header of the inline compressed offsets (44-byte blocks).
  const std::size_t offsets_blocks = (179 * (zlib_le.OffsetsInt64() ? 8 : 4) + 43) / 44;
  const std::size_t offsets_header_chars = ((3 + offsets_blocks) * 4 + 2) / 3 * 4;
  const std::uint64_t points_bytes = 3 * 8 * static_cast<std::uint64_t>(box.num_nodes());

  const std::vector<Mistake> mistakes = {
      {"malformed_xml", Replaced(a, "</Cells>", "</Cels>"), "malformed XML"},
      {"comment", Replaced(i, "<!-- connectivity", "<!- connectivity"), "malformed XML"},
      {"no_root", Replaced(Replaced(a, "<VTKFile ", "<VTKFil "), "</VTKFile>", "</VTKFil>"),
       "expected a <VTKFile> root element"},
      {"vtkfile_type", Replaced(i, R"(type="UnstructuredGrid")", R"(type="PolyData")"),
       "line 3 (<VTKFile>): expected type=\"UnstructuredGrid\""},
      {"byte_order", Replaced(i, R"(byte_order="LittleEndian")", R"(byte_order="Middle")"),
       "expected byte_order LittleEndian or BigEndian"},
      {"header_type", Replaced(s, R"(header_type="UInt64")", R"(header_type="UInt16")"),
       "expected header_type UInt32 or UInt64"},
      {"compressor", Replaced(z, "vtkZLibDataCompressor", "vtkLZ4DataCompressor"),
       "unsupported compressor"},
      {"no_grid",
       Replaced(Replaced(a, "<UnstructuredGrid>", "<Unstructured>"), "</UnstructuredGrid>",
                "</Unstructured>"),
       "expected an <UnstructuredGrid> element"},
      {"no_piece", Replaced(Replaced(r, "<Piece ", "<Peace "), "</Piece>", "</Peace>"),
       "expected at least one <Piece>"},
      {"point_count", Replaced(i, R"(NumberOfPoints="45")", R"(NumberOfPoints="4x5")"),
       "expected a non-negative integer attribute NumberOfPoints"},
      {"cell_count", Replaced(rz, R"(NumberOfCells="179")", R"(NumberOfCells="-179")"),
       "expected a non-negative integer attribute NumberOfCells"},
      {"no_points_array",
       Replaced(Replaced(a, R"(<DataArray Name="Points")", R"(<DataArrax Name="Points")"),
                "</DataArray>", "</DataArrax>", R"(Name="Points")"),
       "expected <Points> with a <DataArray>"},
      {"components", Replaced(s, R"(NumberOfComponents="3")", R"(NumberOfComponents="2")"),
       "expected NumberOfComponents=\"3\""},
      {"float16",
       Replaced(r, fmt::format(R"(Name="Points" type="{}")", raw_le.PointsType()),
                R"(Name="Points" type="Float16")"),
       "unsupported type"},
      {"float_connectivity",
       Replaced(i, fmt::format(R"(Name="connectivity" type="{}")", inline_le.ConnectivityType()),
                R"(Name="connectivity" type="Float32")"),
       "expected an integer type"},
      {"float_types", Replaced(a, R"(Name="types" type="UInt8")", R"(Name="types" type="Float64")"),
       "expected an integer type"},
      {"format", Replaced(i, R"(format="binary")", R"(format="hex")", R"(Name="offsets")"),
       "expected format ascii, binary or appended"},
      {"no_cells", Replaced(Replaced(s, "<Cells>", "<Cellz>"), "</Cells>", "</Cellz>"),
       "expected a <Cells> element"},
      {"no_offsets", Replaced(z, R"(Name="offsets")", R"(Name="offset")"),
       "expected a <DataArray Name=\"offsets\">"},
      {"no_types", Replaced(b, R"(Name="types")", R"(Name="type")"),
       "expected a <DataArray Name=\"types\">"},
      {"no_connectivity", Replaced(a, R"(Name="connectivity")", R"(Name="conn")"),
       "expected a <DataArray Name=\"connectivity\">"},
      {"nan_ascii", Replaced(a, "0.5", "nan", R"(Name="Points")"), "expected a finite number, got"},
      {"not_a_number_ascii", Replaced(a, " 1 ", " 1x ", R"(Name="Points")"),
       "expected a finite number, got"},
      {"not_an_integer_ascii", Replaced(a, " 10 ", " 10.5 ", R"(Name="types")"),
       "expected an integer, got"},
      {"nan_appended_raw", CellsAsVtu(nan.nodes, BoxCells(box), raw_le), "value 10 is not finite"},
      {"inf_inline_zlib", CellsAsVtu(inf.nodes, BoxCells(box), zlib_le), "value 122 is not finite"},
      {"too_few_points_ascii", Replaced(a, R"(NumberOfPoints="45")", R"(NumberOfPoints="46")"),
       "expected 138 values, got 135"},
      {"too_many_points_ascii", Replaced(a, R"(NumberOfPoints="45")", R"(NumberOfPoints="44")"),
       "expected 132 values, got 135"},
      {"too_many_types_ascii", Replaced(a, "</DataArray>", " 10</DataArray>", R"(Name="types")"),
       "expected 179 values, got 180"},
      {"too_few_connectivity_ascii",
       Replaced(a, ">\n          0 ", ">\n          ", R"(Name="connectivity")"), "values, got"},
      {"falling_offsets_ascii",
       Replaced(a, ">\n          1 5 9 ", ">\n          1 9 5 ", R"(Name="offsets")"),
       "offset 5 of cell 2 is below the previous 9"},
      {"falling_offsets_binary",
       Patched<std::int32_t>(r, AppendedStart(r, "offsets") + 4 + 2 * 4, 3, raw_le),
       "offset 3 of cell 2 is below the previous 5"},
      {"three_point_tet",
       cells([](std::vector<VtkCell>& c) { c[5].points.pop_back(); }, separate_be),
       "expected 4 point indices for a tetrahedron (cell 5), got 3"},
      {"four_point_triangle",
       cells([](std::vector<VtkCell>& c) { c.back().points.push_back(44); }, base64_le),
       "expected 3 point indices for a triangle (cell 178), got 4"},
      {"out_of_range", cells([](std::vector<VtkCell>& c) { c[6].points[2] = 45; }, raw_zlib_be),
       "cell 6 refers to point 45, out of range [0, 45)"},
      {"negative_index", cells([](std::vector<VtkCell>& c) { c[150].points[0] = -1; }, base64_le),
       "cell 150 refers to point -1, out of range [0, 45)"},
      {"repeated_point",
       cells([](std::vector<VtkCell>& c) { c[8].points[2] = c[8].points[0]; }, base64_zlib_be),
       "cell 8 repeats point"},
      {"header_bytes", WithHeaderWord(r, AppendedStart(r, "Points"), points_bytes - 8, raw_le),
       fmt::format("expected {} bytes of data, the block header says {}", points_bytes,
                   points_bytes - 8)},
      {"compressed_header_bytes",
       WithHeaderWord(rz, AppendedStart(rz, "offsets") + 16, 5, raw_zlib_be),
       "bytes of data, the compressed header says"},
      {"compressed_block_count",
       WithHeaderWord(rz, AppendedStart(rz, "types"), 1000000, raw_zlib_be),
       "compressed header declares too many blocks"},
      {"truncated_appended_raw", r.substr(0, r.size() - end.size() - 3),
       "expected 179 bytes of data, only 176 present"},
      {"truncated_appended_raw_zlib", rz.substr(0, rz.size() - end.size() - 3), "is truncated"},
      {"truncated_points", r.substr(0, AppendedStart(r, "Points") + 100),
       "expected 1080 bytes of data, only 96 present"},
      // Files cut short: in the markup, in an array's text, just after the '<' that would
      // close an array, in appended data.
      {"cut_in_markup", a.substr(0, a.find("<Cells>") + 4),
       "malformed XML: Error parsing start element tag"},
      {"cut_after_open_bracket", a.substr(0, a.find("<Cells>") + 1),
       "malformed XML: Could not determine tag type"},
      {"cut_in_ascii_connectivity", a.substr(0, a.find(R"(Name="connectivity")") + 700),
       "line 84: malformed XML: Start-end tags mismatch"},
      {"cut_in_inline_points",
       i.substr(0, i.find("</InformationKey>", i.find(R"(Name="Points")")) + 17 + 11 + 100),
       "line 26: malformed XML: Start-end tags mismatch"},
      {"cut_after_open_bracket_after_data",
       i.substr(0, i.find("\n        </DataArray>", i.find(R"(Name="connectivity")")) + 10),
       "malformed XML: Start-end tags mismatch"},
      {"cut_in_appended_header", rz.substr(0, AppendedStart(rz, "offsets") + 20),
       "compressed header declares too many blocks"},
      {"cut_in_appended_offsets", rz.substr(0, AppendedStart(rz, "offsets") + 400),
       "(<DataArray Name=\"offsets\">): compressed block 2 is truncated"},
      {"bad_base64_inline", Replaced(i, "==", "=*", R"(Name="connectivity")"),
       "invalid base64 at character"},
      {"bad_base64_appended", WithChar(b, AppendedStart(b, "connectivity") + 30, '!'),
       "invalid base64 in AppendedData at"},
      {"bad_base64_appended_last_array", WithChar(b, AppendedStart(b, "types") + 5, '-'),
       "invalid base64 in AppendedData at"},
      {"short_base64_inline", std::string(i).erase(InlineStart(i, "connectivity") + 12, 40),
       "bytes of data, only"},
      {"corrupt_zlib", FlipBase64(z, "connectivity", 10), "is corrupt"},
      {"corrupt_zlib_first_block",
       Flipped(z, InlineStart(z, "offsets") + offsets_header_chars + 20),
       "compressed block 0 is corrupt"},
      {"offset_beyond", Replaced(r, R"(offset=")", R"(offset="99999)", R"(Name="connectivity")"),
       "is beyond the appended data"},
      {"no_underscore", Replaced(b, "\n   _", "\n   ", "<AppendedData"),
       "expected '_' starting the <AppendedData> content"},
  };
  for (const Mistake& m : mistakes) {
    const auto path = WriteBytes(Scratch(m.name + ".vtu"), m.text);
    const std::string whole = InputErrorMessage([&] { (void)ReadVtu(path); });
    EXPECT_THAT(whole, HasSubstr(m.says)) << m.name;
    for (int size : {1, 3}) {
      for (int rank = 0; rank < size; ++rank) {
        EXPECT_EQ(InputErrorMessage([&] { (void)ReadVtuBlock(path, rank, size); }), whole)
            << m.name << ", block " << rank << " of " << size;
      }
    }
  }
  const std::string missing = "/nonexistent/x.vtu";
  EXPECT_EQ(InputErrorMessage([&] { (void)ReadVtuBlock(missing, 0, 2); }),
            InputErrorMessage([&] { (void)ReadVtu(missing); }));
}

// Every strict prefix of a file, with appended raw compressed data or inline base64, is refused
// by the block reader exactly when the whole reader refuses it, with its message (or left to
// the whole reader), and otherwise gives the whole reader's block: a cut file never yields a
// partial block.
TEST(VtuBlockReader, EveryTruncationIsRefusedExactlyWhenTheWholeReaderRefusesIt) {
  const Mesh box = MakeTetBox(Vec3::Zero(), Vec3(1, 1, 1), {1, 1, 1});
  for (const Variant& v :
       {Variant{Layout::kAppendedRawZlib, false, false}, Variant{Layout::kInline, true, true}}) {
    const std::string bytes = BoxAsVtu(box, v);
    const auto path = Scratch("cut_" + v.FileName());
    std::size_t refused = 0;
    for (std::size_t n = 0; n < bytes.size(); ++n) {
      WriteBytes(path, std::string_view(bytes).substr(0, n));
      std::optional<Mesh> whole;
      std::string whole_message;
      try {
        whole = ReadVtu(path);
      } catch (const InputError& e) {
        whole_message = e.what();
      }
      for (int rank : {0, 1}) {
        const std::string what =
            fmt::format("{}: {} of {} bytes, block {} of 2", v.Describe(), n, bytes.size(), rank);
        std::optional<MeshBlock> block;
        bool block_refused = false;
        try {
          block = ReadVtuBlock(path, rank, 2);
        } catch (const InputError& e) {
          block_refused = true;
          // One mistake (the cut), so the whole reader's message, word for word.
          if (!whole) {
            ASSERT_EQ(e.what(), whole_message) << what;
          }
        }
        if (whole) {
          ASSERT_FALSE(block_refused) << what;
          ASSERT_TRUE(block.has_value()) << what;
          test::ExpectSameBlock(*block, BlockOfMesh(*whole, rank, 2), what);
        } else {
          // Refused, or left to the whole reader (which refuses it).
          ASSERT_TRUE(block_refused || !block.has_value()) << what;
        }
      }
      refused += whole ? 0 : 1;
    }
    EXPECT_GE(refused, bytes.size() * 8 / 10) << v.Describe();
  }
}

// Mistakes in what ReadVtu does not read (point and cell data, field data, cells of other types,
// the cells of a piece that declares none) are not mistakes to the block reader either: the
// whole reader reads these files and every block is its slice.
TEST(VtuBlockReader, MistakesInWhatTheReadersSkipAreSkippedByBoth) {
  const Mesh box = Box();
  const Variant ascii{Layout::kAscii, false, false};
  const Variant inline_le{Layout::kInline, false, false};
  const Variant zlib_le{Layout::kInlineZlib, false, false};
  const Variant base64_le{Layout::kAppendedBase64, true, false};
  const std::string a = BoxAsVtu(box, ascii), i = BoxAsVtu(box, inline_le);
  const std::string z = BoxAsVtu(box, zlib_le), b = BoxAsVtu(box, base64_le);
  std::vector<VtkCell> stray = BoxCells(box);
  for (VtkCell& cell : stray) {
    if (cell.type == 3) cell.points = {-5, 999, 7, 7};  // a line of four points, out of range
    if (cell.type == 2) cell.points = {45};             // a vertex beyond the last point
  }
  const std::vector<std::pair<std::string, std::string>> files = {
      {"nan_point_data", Replaced(a, ">\n          0 ", ">\n          nan ", R"(Name="x")")},
      {"point_data_format", Replaced(a, R"(format="ascii")", R"(format="hex")", R"(Name="x")")},
      {"point_data_corrupt_zlib", FlipBase64(z, "x", 10)},
      {"cell_data_base64", WithChar(i, InlineStart(i, "kind") + 5, '*')},
      {"cell_data_type",
       Replaced(z, R"(Name="kind" type="Int32")", R"(Name="kind" type="Float16")")},
      {"appended_cell_data_base64", WithChar(b, AppendedStart(b, "kind") + 5, '*')},
      {"field_data",
       Replaced(a, "<UnstructuredGrid>\n",
                "<UnstructuredGrid>\n    <FieldData>\n      <DataArray type=\"Float64\" "
                "Name=\"TimeValue\" NumberOfTuples=\"1\" format=\"ascii\">x</DataArray>\n"
                "    </FieldData>\n")},
      {"stray_cells", CellsAsVtu(box.nodes, stray, zlib_le)},
      {"no_cells_declared", Replaced(i, R"(NumberOfCells="179")", R"(NumberOfCells="0")")},
  };
  for (const auto& [name, text] : files) {
    const auto path = WriteBytes(Scratch(name + ".vtu"), text);
    std::optional<Mesh> whole;
    try {
      whole = ReadVtu(path);
    } catch (const InputError& e) {
      ADD_FAILURE() << name << ": the whole reader refuses it: " << e.what();
      continue;
    }
    for (int size : {1, 2}) {
      for (int rank = 0; rank < size; ++rank) {
        std::optional<MeshBlock> block;
        try {
          block = ReadVtuBlock(path, rank, size);
        } catch (const InputError& e) {
          ADD_FAILURE() << name << ": the block reader refuses it: " << e.what();
          continue;
        }
        ASSERT_TRUE(block.has_value()) << name;
        test::ExpectSameBlock(*block, BlockOfMesh(*whole, rank, size),
                              fmt::format("{}, block {} of {}", name, rank, size));
      }
    }
  }
}

// Arrays of megabytes, larger than the block reader's buffers, in text, base64 and compressed
// form: every block is still the whole reader's slice.
TEST(VtuBlockReader, ArraysLargerThanItsBuffersAreReadThrough) {
  const Mesh box = MakeTetBox(Vec3::Zero(), Vec3(3, 3, 3), {24, 24, 24});
  for (const Variant& v :
       {Variant{Layout::kAscii, false, false}, Variant{Layout::kInlineSeparateHeader, true, true},
        Variant{Layout::kAppendedRawZlib, false, false},
        Variant{Layout::kAppendedBase64, false, true}}) {
    const auto path = WriteBytes(Scratch(v.FileName()), BoxAsVtu(box, v));
    ASSERT_GT(std::filesystem::file_size(path), 3u << 20) << v.Describe();
    const Mesh whole = ReadVtu(path);
    ASSERT_EQ(whole.num_tets(), box.num_tets()) << v.Describe();
    for (int rank = 0; rank < 3; ++rank) {
      const auto block = ReadVtuBlock(path, rank, 3);
      ASSERT_TRUE(block.has_value()) << v.Describe();
      test::ExpectSameBlock(*block, BlockOfMesh(whole, rank, 3),
                            fmt::format("{}, block {} of 3", v.Describe(), rank));
    }
  }
}

}  // namespace
}  // namespace gipsi
