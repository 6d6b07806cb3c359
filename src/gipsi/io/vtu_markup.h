#pragma once
/// @file
/// Internal helper of the VTU readers (vtu_reader.h: the whole file; vtu_block_reader.h: one
/// process's block): the checks of a parsed file's markup and the messages that name its
/// elements, the same in both. Not part of the public API.

#include <algorithm>
#include <cstdint>
#include <string>
#include <string_view>
#include <utility>

#include <fmt/format.h>
#include <pugixml.hpp>

#include "gipsi/base/error.h"
#include "gipsi/io/text_reader.h"

namespace gipsi::internal {

/// How a file stores its arrays' binary data, from its <VTKFile> element.
struct VtuEncoding {
  bool swap = false;        // its byte order is not the host's
  bool compressed = false;  // vtkZLibDataCompressor
  int header_bytes = 4;     // UInt32 or UInt64 header words
};

/// A VTU file's markup, parsed: messages name the file and the line of an element, counted in
/// `lines` (text whose lines are the file's, the offsets the parser's).
class VtuMarkup {
 public:
  explicit VtuMarkup(std::string source) : source_(std::move(source)) {}

  /// The text lines are counted in (the file, or the markup as parsed when it keeps the
  /// file's lines); it must outlive the messages.
  void set_lines(std::string_view lines) { lines_ = lines; }
  [[nodiscard]] const std::string& source() const { return source_; }

  int LineOfOffset(std::size_t offset) const {
    offset = std::min(offset, lines_.size());
    return 1 + static_cast<int>(std::count(
                   lines_.begin(), lines_.begin() + static_cast<std::ptrdiff_t>(offset), '\n'));
  }

  /// Parses `xml` into `doc`; InputError naming the line for malformed XML.
  void Parse(pugi::xml_document& doc, std::string_view xml) const {
    pugi::xml_parse_result ok = doc.load_buffer(xml.data(), xml.size());
    if (!ok)
      ThrowInputError(source_, fmt::format("line {}", LineOfOffset(std::size_t(ok.offset))),
                      fmt::format("malformed XML: {}", ok.description()));
  }

  /// The document's <UnstructuredGrid>, and how its root stores binary data, each checked.
  pugi::xml_node Grid(const pugi::xml_document& doc, VtuEncoding* encoding) const {
    pugi::xml_node root = doc.child("VTKFile");
    if (!root) ThrowInputError(source_, "", "expected a <VTKFile> root element");
    std::string_view type = root.attribute("type").value();
    if (type != "UnstructuredGrid")
      Fail(root, fmt::format("expected type=\"UnstructuredGrid\", got {}", Quote(type)));
    std::string_view order = root.attribute("byte_order").value();
    bool little = order.empty() || order == "LittleEndian";
    if (!little && order != "BigEndian")
      Fail(root,
           fmt::format("expected byte_order LittleEndian or BigEndian, got {}", Quote(order)));
    encoding->swap = little != HostIsLittleEndian();
    std::string_view header = root.attribute("header_type").value();
    if (header == "UInt64") {
      encoding->header_bytes = 8;
    } else if (!header.empty() && header != "UInt32") {
      Fail(root, fmt::format("expected header_type UInt32 or UInt64, got {}", Quote(header)));
    }
    std::string_view compressor = root.attribute("compressor").value();
    encoding->compressed = !compressor.empty();
    if (encoding->compressed && compressor != "vtkZLibDataCompressor")
      Fail(root, fmt::format("unsupported compressor {} (supported: vtkZLibDataCompressor)",
                             Quote(compressor)));
    pugi::xml_node grid = root.child("UnstructuredGrid");
    if (!grid) Fail(root, "expected an <UnstructuredGrid> element");
    return grid;
  }

  [[noreturn]] void Fail(const pugi::xml_node& node, std::string_view what) const {
    std::string name = node.attribute("Name").value();
    ThrowInputError(source_,
                    fmt::format("line {} (<{}{}>)", LineOfOffset(std::size_t(node.offset_debug())),
                                node.name(), name.empty() ? "" : " Name=\"" + name + "\""),
                    what);
  }

  std::uint64_t Attribute(const pugi::xml_node& node, const char* name) const {
    std::string_view text = node.attribute(name).value();
    std::int64_t v = 0;
    if (!TryParseInt(text, &v) || v < 0)
      Fail(node,
           fmt::format("expected a non-negative integer attribute {}, got {}", name, Quote(text)));
    return static_cast<std::uint64_t>(v);
  }

  pugi::xml_node FindArray(const pugi::xml_node& parent, const char* name) const {
    for (pugi::xml_node a : parent.children("DataArray"))
      if (std::string_view(a.attribute("Name").value()) == name) return a;
    Fail(parent, fmt::format("expected a <DataArray Name=\"{}\">", name));
  }

  /// The <Points> array of a piece, checked to have three components.
  pugi::xml_node PointsArray(const pugi::xml_node& piece) const {
    pugi::xml_node points = piece.child("Points").child("DataArray");
    if (!points) Fail(piece, "expected <Points> with a <DataArray>");
    if (std::string_view c = points.attribute("NumberOfComponents").value(); c != "3")
      Fail(points, fmt::format("expected NumberOfComponents=\"3\", got {}", Quote(c)));
    return points;
  }

 private:
  std::string source_;
  std::string_view lines_;
};

}  // namespace gipsi::internal
