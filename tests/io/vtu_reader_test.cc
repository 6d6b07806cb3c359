#include "gipsi/io/vtu_reader.h"

#include <algorithm>
#include <cstdint>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "gipsi/io/base64.h"
#include "io/io_test_util.h"

namespace gipsi {
namespace {

using test::CountRejectedPrefixes;
using test::ExpectTwoTetsAndTriangle;
using test::InputErrorMessage;
using test::MeshData;
using test::Put;
using test::Scratch;
using test::StoredZlib;
using test::WriteBytes;
using ::testing::HasSubstr;

enum class Encoding { kInline, kInlineSeparateHeader, kZlib, kAppendedRaw };

/// Writes the header word of a binary block (UInt32 or UInt64).
void PutHeader(std::string& out, std::uint64_t v, bool header64) {
  if (header64)
    Put<std::uint64_t>(out, v);
  else
    Put<std::uint32_t>(out, static_cast<std::uint32_t>(v));
}

/// The binary block (header + data) of `payload` as VTK lays it out.
std::string Block(std::string_view payload, Encoding enc, bool header64) {
  std::string out;
  if (enc != Encoding::kZlib) {
    PutHeader(out, payload.size(), header64);
    if (enc == Encoding::kInlineSeparateHeader)
      return internal::EncodeBase64(out) + internal::EncodeBase64(payload);
    out.append(payload);
    return enc == Encoding::kInline ? internal::EncodeBase64(out) : out;
  }
  const std::size_t kBlock = 40;  // small, so that there are several blocks
  std::vector<std::string> blocks;
  for (std::size_t p = 0; p < payload.size(); p += kBlock)
    blocks.push_back(StoredZlib(payload.substr(p, kBlock)));
  PutHeader(out, blocks.size(), header64);
  PutHeader(out, kBlock, header64);
  PutHeader(out, payload.size() % kBlock, header64);
  for (const auto& b : blocks) PutHeader(out, b.size(), header64);
  std::string data;
  for (const auto& b : blocks) data += b;
  return internal::EncodeBase64(out) + internal::EncodeBase64(data);
}

template <class T>
std::string Bytes(std::initializer_list<T> values) {
  std::string out;
  for (T v : values) Put(out, v);
  return out;
}

/// Two tets, a triangle and a line (VTK type 3) as a binary .vtu.
std::string TwoTetsVtu(Encoding enc, bool header64) {
  std::vector<std::pair<std::string, std::string>> arrays = {
      {R"(type="Float64" NumberOfComponents="3")",
       Bytes<double>({0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 1, 1})},
      {R"(type="Int64" Name="connectivity")",
       Bytes<std::int64_t>({0, 1, 2, 3, 1, 2, 3, 4, 0, 1, 2, 0, 4})},
      {R"(type="Int32" Name="offsets")", Bytes<std::int32_t>({4, 8, 11, 13})},
      {R"(type="UInt8" Name="types")", Bytes<std::uint8_t>({10, 10, 5, 3})}};
  std::string appended;
  std::vector<std::string> xml_arrays;
  for (auto& [attributes, payload] : arrays) {
    std::string block = Block(payload, enc, header64);
    if (enc == Encoding::kAppendedRaw) {
      xml_arrays.push_back("<DataArray " + attributes + R"( format="appended" offset=")" +
                           std::to_string(appended.size()) + "\"/>");
      appended += block;
    } else {
      xml_arrays.push_back("<DataArray " + attributes + R"( format="binary">)" + block +
                           "</DataArray>");
    }
  }
  std::string s = "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" ";
  s += test::LittleEndianHost() ? "byte_order=\"LittleEndian\"" : "byte_order=\"BigEndian\"";
  s += header64 ? " header_type=\"UInt64\"" : " header_type=\"UInt32\"";
  if (enc == Encoding::kZlib) s += " compressor=\"vtkZLibDataCompressor\"";
  s += ">\n<UnstructuredGrid>\n<Piece NumberOfPoints=\"5\" NumberOfCells=\"4\">\n<Points>\n";
  s += xml_arrays[0] + "\n</Points>\n<Cells>\n";
  s += xml_arrays[1] + "\n" + xml_arrays[2] + "\n" + xml_arrays[3] + "\n</Cells>\n";
  s += "</Piece>\n</UnstructuredGrid>\n";
  if (enc == Encoding::kAppendedRaw)
    s += "<AppendedData encoding=\"raw\">\n_" + appended + "\n</AppendedData>\n";
  s += "</VTKFile>\n";
  return s;
}

Mesh ReadGenerated(Encoding enc, bool header64) {
  return ReadVtu(WriteBytes(Scratch("g.vtu"), TwoTetsVtu(enc, header64)));
}

TEST(VtuReader, ReadsAsciiArraysKeepingTetsAndTrianglesOnly) {
  ExpectTwoTetsAndTriangle(ReadVtu(MeshData("two_tets_ascii.vtu")));
}

TEST(VtuReader, ReadsInlineBase64WithUInt32Header) {
  ExpectTwoTetsAndTriangle(ReadGenerated(Encoding::kInline, false));
}

TEST(VtuReader, ReadsInlineBase64WithUInt64Header) {
  ExpectTwoTetsAndTriangle(ReadGenerated(Encoding::kInline, true));
}

TEST(VtuReader, ReadsInlineBase64WithSeparatelyEncodedHeader) {
  ExpectTwoTetsAndTriangle(ReadGenerated(Encoding::kInlineSeparateHeader, false));
}

TEST(VtuReader, ReadsZlibCompressedWithUInt32Header) {
  ExpectTwoTetsAndTriangle(ReadGenerated(Encoding::kZlib, false));
}

TEST(VtuReader, ReadsZlibCompressedWithUInt64Header) {
  ExpectTwoTetsAndTriangle(ReadGenerated(Encoding::kZlib, true));
}

TEST(VtuReader, ReadsAppendedRawData) {
  ExpectTwoTetsAndTriangle(ReadGenerated(Encoding::kAppendedRaw, false));
  ExpectTwoTetsAndTriangle(ReadGenerated(Encoding::kAppendedRaw, true));
}

TEST(VtuReader, RejectsOutOfRangeIndexNamingLineAndArray) {
  std::string s = test::ReadBytes(MeshData("two_tets_ascii.vtu"));
  s.replace(s.find("0 1 2 3 1 2 3 4"), 15, "0 1 2 3 1 2 3 9");
  auto path = WriteBytes(Scratch("range.vtu"), s);
  EXPECT_EQ(InputErrorMessage([&] { ReadVtu(path); }),
            path.string() +
                ": line 15 (<DataArray Name=\"connectivity\">): cell 1 refers to point 9, out of "
                "range [0, 5)");
}

TEST(VtuReader, RejectsWrongValueCount) {
  std::string s = test::ReadBytes(MeshData("two_tets_ascii.vtu"));
  s.replace(s.find(">4 8 11 13<"), 11, ">4 8 11<");
  EXPECT_THAT(InputErrorMessage([&] { ReadVtu(WriteBytes(Scratch("n.vtu"), s)); }),
              HasSubstr("line 16 (<DataArray Name=\"offsets\">): expected 4 values, got 3"));
}

TEST(VtuReader, RejectsMalformedXmlWithLine) {
  std::string s = test::ReadBytes(MeshData("two_tets_ascii.vtu"));
  s.replace(s.find("</Cells>"), 8, "</Cels>");
  EXPECT_THAT(InputErrorMessage([&] { ReadVtu(WriteBytes(Scratch("x.vtu"), s)); }),
              HasSubstr("line 18: malformed XML: Start-end tags mismatch"));
}

TEST(VtuReader, RejectsTruncatedBinaryBlock) {
  std::string s = TwoTetsVtu(Encoding::kInline, false);
  std::size_t start = s.find("format=\"binary\">") + 16;
  s.erase(start + 8, 40);  // drop 30 bytes of coordinates
  EXPECT_THAT(InputErrorMessage([&] { ReadVtu(WriteBytes(Scratch("t.vtu"), s)); }),
              HasSubstr("expected 120 bytes of data, only 90 present"));
}

TEST(VtuReader, RejectsCorruptCompressedBlock) {
  std::string s = TwoTetsVtu(Encoding::kZlib, false);
  std::size_t start = s.find("format=\"binary\">") + 16;
  s[start + 60] = s[start + 60] == 'A' ? 'B' : 'A';
  EXPECT_THAT(InputErrorMessage([&] { ReadVtu(WriteBytes(Scratch("z.vtu"), s)); }),
              HasSubstr("is corrupt"));
}

TEST(VtuReader, RejectsHugeDeclaredPointCountBeforeAllocating) {
  std::string s = TwoTetsVtu(Encoding::kZlib, true);
  s.replace(s.find("NumberOfPoints=\"5\""), 18, "NumberOfPoints=\"900000000\"");
  EXPECT_THAT(InputErrorMessage([&] { ReadVtu(WriteBytes(Scratch("h.vtu"), s)); }),
              HasSubstr("expected 21600000000 bytes of data"));
}

TEST(VtuReader, SurvivesEveryTruncationOfAppendedData) {
  const std::string bytes = TwoTetsVtu(Encoding::kAppendedRaw, false);
  const std::size_t rejected =
      CountRejectedPrefixes(bytes, Scratch("cut.vtu"), [](const auto& p) { return ReadVtu(p); });
  // Only cuts inside the trailing data the reader ignores give a mesh (the whole one, checked
  // above); every cut before the connectivity ends is rejected.
  EXPECT_GE(rejected, bytes.size() * 8 / 10);
}

TEST(VtuReader, RejectsMissingFile) {
  EXPECT_EQ(InputErrorMessage([] { ReadVtu("/nonexistent/x.vtu"); }),
            "/nonexistent/x.vtu: cannot open mesh file for reading: No such file or directory");
}

}  // namespace
}  // namespace gipsi
