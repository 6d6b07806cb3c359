/// @file
/// One block of a VTK XML unstructured grid, streamed (see vtu_block_reader.h). ReadVtu
/// (vtu_reader.cc) holds the file and decodes each array whole; here the same checks run on
/// arrays decoded front to back, so the messages are ReadVtu's.

#include "gipsi/io/vtu_block_reader.h"

#include <zlib.h>

#include <algorithm>
#include <climits>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <string>
#include <string_view>
#include <unordered_map>
#include <utility>
#include <vector>

#include <fmt/format.h>
#include <pugixml.hpp>

#include "gipsi/base/error.h"
#include "gipsi/io/base64.h"
#include "gipsi/io/chunked_file.h"
#include "gipsi/io/text_reader.h"
#include "gipsi/io/vtk_legacy_types.h"
#include "gipsi/io/vtu_markup.h"

namespace gipsi {
namespace {

using internal::ChunkedFile;
using internal::LoadScalar;
using internal::Quote;
using internal::VtkDataType;

constexpr std::size_t kPiece = std::size_t{1} << 16;  // bytes decoded at a time

/// Where a <DataArray>'s own text (its first run of characters that is not all blank, which
/// pugixml's text() gives) lies in the file.
struct ArrayText {
  std::uint64_t begin = 0, end = 0;
  bool found = false;
};

/// What the first pass finds: the file's markup with the arrays' text left out (their line
/// breaks kept, so that lines count as in the file, and a '0' for each run of text), and where
/// the data is.
struct Markup {
  std::string xml;
  std::vector<ArrayText> texts;  // every <DataArray> in document order
  bool cdata = false;
  bool appended = false, appended_base64 = false;
  std::uint64_t appended_begin = 0, appended_end = 0;  // after the '_'; the end of its data
  int appended_line = 0;
};

std::size_t Lines(std::string_view text) {
  return static_cast<std::size_t>(std::count(text.begin(), text.end(), '\n'));
}
int LinesIn(std::string_view text) { return static_cast<int>(Lines(text)); }

/// The decoded bytes of [begin, end) of a file: the bytes themselves, or the base64 text there
/// decoded (already checked by Base64Size).
class ByteStream {
 public:
  ByteStream(const std::filesystem::path& path, std::uint64_t begin, std::uint64_t end, bool base64)
      : file_(path), base64_(base64) {
    file_.Seek(begin, end);
  }
  /// Copies the next `n` bytes to `out`; fewer only at the end.
  std::size_t Read(char* out, std::size_t n) {
    std::size_t done = 0;
    while (done < n) {
      if (!base64_) {
        const std::string_view bytes = file_.Take(n - done);
        if (bytes.empty()) break;
        std::memcpy(out + done, bytes.data(), bytes.size());
        done += bytes.size();
        continue;
      }
      if (pos_ == decoded_.size()) {
        decoded_.clear();
        pos_ = 0;
        if (ended_) break;
        const std::string_view text = file_.Take(kPiece);
        if (text.empty()) {
          ended_ = true;
          (void)decoder_.Finish(decoded_);
        } else if (!decoder_.Feed(text, decoded_)) {
          ended_ = true;
        }
        continue;
      }
      const std::size_t k = std::min(n - done, decoded_.size() - pos_);
      std::memcpy(out + done, decoded_.data() + pos_, k);
      pos_ += k;
      done += k;
    }
    return done;
  }

 private:
  ChunkedFile file_;
  bool base64_;
  internal::Base64Decoder decoder_;
  std::string decoded_;
  std::size_t pos_ = 0;
  bool ended_ = false;
};

class VtuBlockParser {
 public:
  VtuBlockParser(const std::filesystem::path& path, int rank, int size)
      : path_(path),
        source_(path.string()),
        file_(path),
        rank_(rank),
        size_(size),
        markup_(source_) {}

  std::optional<MeshBlock> Read() {
    if (!ScanMarkup()) return std::nullopt;
    markup_.set_lines(m_.xml);
    pugi::xml_document doc;
    markup_.Parse(doc, m_.xml);
    NumberArrays(doc);
    internal::VtuEncoding encoding;
    pugi::xml_node grid = markup_.Grid(doc, &encoding);
    swap_ = encoding.swap;
    compressed_ = encoding.compressed;
    header_bytes_ = encoding.header_bytes;
    auto pieces = grid.children("Piece");
    if (pieces.begin() == pieces.end()) Fail(grid, "expected at least one <Piece>");
    if (std::next(pieces.begin()) != pieces.end()) return std::nullopt;
    if (!ReadPiece(*pieces.begin())) return std::nullopt;
    return std::move(block_);
  }

 private:
  /// One <DataArray>'s values, decoded front to back and checked as ReadVtu checks them.
  class Array {
   public:
    // Checks the type, the format and a binary array's header, as ReadVtu does before it
    // converts the values.
    Array(VtuBlockParser& p, const pugi::xml_node& node, std::uint64_t count, bool want_int)
        : p_(p), node_(node), count_(count) {
      std::string_view type_name = node.attribute("type").value();
      type_ = internal::ParseVtuDataType(type_name);
      if (type_.bytes == 0) p.Fail(node, fmt::format("unsupported type {}", Quote(type_name)));
      if (want_int && type_.is_float) p.Fail(node, "expected an integer type");
      std::string_view format = node.attribute("format").value();
      const ArrayText& text = p.TextOf(node);
      if (format == "ascii") {
        OpenAscii(text);
        return;
      }
      if (count > std::numeric_limits<std::uint64_t>::max() / 8) p.Fail(node, "array is too large");
      want_ = count * static_cast<std::uint64_t>(type_.bytes);
      if (format == "binary") {
        const std::uint64_t begin = text.found ? text.begin : 0, end = text.found ? text.end : 0;
        std::size_t bad = 0;
        auto present = Base64Size(begin, end, &bad);
        if (!present) p.Fail(node, fmt::format("invalid base64 at character {}", bad));
        OpenBinary(begin, end, true, *present);
      } else if (format == "appended") {
        const std::uint64_t offset = p.Attribute(node, "offset");
        const std::uint64_t size = p.m_.appended_end - p.m_.appended_begin;  // 0 if none
        if (offset > size)
          p.Fail(node, fmt::format("offset {} is beyond the appended data ({} bytes, line {})",
                                   offset, size, p.m_.appended_line));
        const std::uint64_t begin = p.m_.appended_begin + offset;
        std::uint64_t present = size - offset;
        if (p.m_.appended_base64) {
          std::size_t bad = 0;
          auto decoded = Base64Size(begin, p.m_.appended_end, &bad);
          if (!decoded)
            p.Fail(node, fmt::format("invalid base64 in AppendedData at {}", offset + bad));
          present = *decoded;
        }
        OpenBinary(begin, p.m_.appended_end, p.m_.appended_base64, present);
      } else {
        p.Fail(node,
               fmt::format("expected format ascii, binary or appended, got {}", Quote(format)));
      }
    }
    ~Array() {
      if (inflating_) inflateEnd(&z_);
    }
    Array(const Array&) = delete;
    Array& operator=(const Array&) = delete;

    /// The next value (there are `count` in all) as an integer, or as a finite real.
    std::int64_t NextInt() {
      if (text_) {
        const std::string_view t = NextToken();
        std::int64_t v = 0;
        if (!internal::TryParseInt(t, &v))
          p_.Fail(node_, fmt::format("expected an integer, got {}", Quote(t)));
        return v;
      }
      return internal::LoadVtkInt(NextBinary(), type_, p_.swap_);
    }
    double NextReal() {
      if (text_) {
        const std::string_view t = NextToken();
        double v = 0;
        if (!internal::TryParseDouble(t, &v) || !std::isfinite(v))
          p_.Fail(node_, fmt::format("expected a finite number, got {}", Quote(t)));
        return v;
      }
      const double v = internal::LoadVtkReal(NextBinary(), type_, p_.swap_);
      if (!std::isfinite(v)) p_.Fail(node_, fmt::format("value {} is not finite", index_ - 1));
      return v;
    }

   private:
    // The size of the base64 text in [begin, end) decoded; nothing (and `bad` its index) for a
    // character that is not base64.
    std::optional<std::uint64_t> Base64Size(std::uint64_t begin, std::uint64_t end,
                                            std::size_t* bad) const {
      ChunkedFile file(p_.path_);
      file.Seek(begin, end);
      internal::Base64Decoder decoder;
      std::string out;
      std::uint64_t size = 0;
      for (std::string_view text = file.Take(internal::kChunk); !text.empty();
           text = file.Take(internal::kChunk)) {
        out.clear();
        if (!decoder.Feed(text, out, bad)) return std::nullopt;
        size += out.size();
      }
      out.clear();
      if (!decoder.Finish(out, bad)) return std::nullopt;
      return size + out.size();
    }

    void OpenAscii(const ArrayText& text) {
      text_.emplace(p_.path_);
      text_->Seek(text.found ? text.begin : 0, text.found ? text.end : 0);
      std::uint64_t tokens = 0;
      std::string_view t;
      while (text_->TryToken(&t)) ++tokens;
      if (tokens != count_)
        p_.Fail(node_, fmt::format("expected {} values, got {}", count_, tokens));
      text_->Seek(text.found ? text.begin : 0, text.found ? text.end : 0);
    }
    std::string_view NextToken() {
      std::string_view t;
      if (!text_->TryToken(&t)) p_.Fail(node_, "fewer values than counted");  // cannot happen
      ++index_;
      return t;
    }

    // A header word of the binary block; `present` bytes decode from its text.
    std::uint64_t Header(std::size_t i) {
      const std::size_t h = static_cast<std::size_t>(p_.header_bytes_);
      if ((i + 1) > present_ / h)
        p_.Fail(node_,
                fmt::format("binary data ends inside its header ({} bytes present)", present_));
      char word[8];
      if (bytes_->Read(word, h) != h) p_.Fail(node_, "binary data ends inside its header");
      return h == 8 ? LoadScalar<std::uint64_t>(word, p_.swap_)
                    : LoadScalar<std::uint32_t>(word, p_.swap_);
    }

    // ReadVtu's Unpack, up to the data: the header's checks against the `present` bytes.
    void OpenBinary(std::uint64_t begin, std::uint64_t end, bool base64, std::uint64_t present) {
      bytes_.emplace(p_.path_, begin, end, base64);
      present_ = present;
      const std::uint64_t h = static_cast<std::uint64_t>(p_.header_bytes_);
      if (!p_.compressed_) {
        std::uint64_t n = Header(0);
        if (n != want_)
          p_.Fail(node_,
                  fmt::format("expected {} bytes of data, the block header says {}", want_, n));
        if (n > present - h)
          p_.Fail(node_, fmt::format("expected {} bytes of data, only {} present (truncated file?)",
                                     n, present - h));
        return;
      }
      std::uint64_t blocks = Header(0);
      if (blocks > present / h) p_.Fail(node_, "compressed header declares too many blocks");
      size_ = Header(1);
      const std::uint64_t last = Header(2);
      if (want_ > internal::kMaxZlibRatio * present + 1024)
        p_.Fail(node_,
                fmt::format("expected {} bytes of data, more than {} compressed bytes can hold "
                            "(wrong count or truncated file?)",
                            want_, present));
      last_size_ = last == 0 ? size_ : last;
      if (blocks > 0 && (size_ == 0 || last_size_ > size_))
        p_.Fail(node_, "inconsistent compressed header");
      std::uint64_t total = 0;
      if (blocks > 1 && blocks - 1 > want_ / size_) {
        total = std::numeric_limits<std::uint64_t>::max();
      } else if (blocks > 0) {
        total = (blocks - 1) * size_ + last_size_;
      }
      if (total != want_)
        p_.Fail(node_,
                fmt::format("expected {} bytes of data, the compressed header says {}", want_,
                            total == std::numeric_limits<std::uint64_t>::max()
                                ? std::string("more")
                                : std::to_string(total)));
      // The compressed sizes: as many as the header holds (ReadVtu finds a missing one when it
      // comes to that block, after the blocks before it).
      for (std::uint64_t b = 0; b < blocks && 3 + b + 1 <= present / h; ++b)
        compressed_sizes_.push_back(Header(3 + std::size_t(b)));
      blocks_ = blocks;
      position_ = h * (3 + blocks);
    }

    // Starts inflating block `block_`, with the checks ReadVtu's Unpack makes before it.
    void StartBlock() {
      if (block_ >= compressed_sizes_.size())
        p_.Fail(node_,
                fmt::format("binary data ends inside its header ({} bytes present)", present_));
      const std::uint64_t csize = compressed_sizes_[block_];
      if (position_ > present_ || csize > present_ - position_)
        p_.Fail(node_, fmt::format("compressed block {} is truncated", block_));
      position_ += csize;
      in_left_ = csize;
      out_left_ = expected_ = block_ + 1 == blocks_ ? last_size_ : size_;
      if (inflating_) inflateEnd(&z_);
      z_ = z_stream{};
      if (inflateInit(&z_) != Z_OK) Corrupt(Z_MEM_ERROR);
      inflating_ = true;
    }
    [[noreturn]] void Corrupt(int rc) const {
      p_.Fail(node_, fmt::format("compressed block {} is corrupt (zlib error {})", block_, rc));
    }
    // Inflates the next bytes of the current block into window_ (starting the next block when
    // none is open). A block is inflated to its end as soon as its last byte is out, and fails
    // with the code zlib's uncompress() would give ReadVtu: a corrupt stream, one that ends
    // before its size, or one that holds more.
    void Inflate() {
      if (!inflating_) StartBlock();
      const auto room = static_cast<std::size_t>(std::min<std::uint64_t>(out_left_, kPiece));
      window_.resize(room);
      window_pos_ = 0;
      z_.next_out = reinterpret_cast<Bytef*>(window_.data());
      z_.avail_out = static_cast<uInt>(room);
      for (;;) {
        if (z_.avail_in == 0 && in_left_ > 0) {
          const auto k = static_cast<std::size_t>(std::min<std::uint64_t>(in_left_, kPiece));
          compressed_.resize(k);
          if (bytes_->Read(compressed_.data(), k) != k) Corrupt(Z_DATA_ERROR);  // checked
          in_left_ -= k;
          z_.next_in = reinterpret_cast<Bytef*>(compressed_.data());
          z_.avail_in = static_cast<uInt>(k);
        }
        const int rc = inflate(&z_, Z_NO_FLUSH);
        if (rc == Z_STREAM_END) {
          if (z_.total_out != expected_) Corrupt(Z_OK);
          inflateEnd(&z_);
          inflating_ = false;
          ++block_;
          break;
        }
        if (rc == Z_NEED_DICT) Corrupt(Z_DATA_ERROR);
        if (rc == Z_BUF_ERROR) {  // no progress: no input left, or no room
          if (z_.total_out == expected_) Corrupt(Z_BUF_ERROR);
          if (z_.avail_in == 0 && in_left_ == 0) Corrupt(Z_DATA_ERROR);
        } else if (rc != Z_OK) {
          Corrupt(rc);
        }
        // Hand out a full window, unless it holds the block's last byte: then its end is due.
        if (z_.avail_out == 0 && z_.total_out < expected_) break;
      }
      window_.resize(room - z_.avail_out);
      out_left_ -= window_.size();
    }
    // Copies the next `n` bytes of the array's data to `out`.
    void Data(char* out, std::size_t n) {
      if (!p_.compressed_) {
        if (bytes_->Read(out, n) != n) p_.Fail(node_, "binary data ends early");  // checked
        return;
      }
      for (std::size_t done = 0; done < n;) {
        if (window_pos_ == window_.size()) Inflate();
        const std::size_t k = std::min(n - done, window_.size() - window_pos_);
        std::memcpy(out + done, window_.data() + window_pos_, k);
        window_pos_ += k;
        done += k;
      }
    }
    const char* NextBinary() {
      const auto bytes = static_cast<std::size_t>(type_.bytes);
      if (pos_ + bytes > buffer_.size()) {
        const std::uint64_t left = want_ - consumed_;
        const auto n = static_cast<std::size_t>(
            std::min<std::uint64_t>(left, kPiece / bytes * bytes));  // whole values
        buffer_.resize(n);
        Data(buffer_.data(), n);
        consumed_ += n;
        pos_ = 0;
      }
      const char* at = buffer_.data() + pos_;
      pos_ += bytes;
      ++index_;
      return at;
    }

    VtuBlockParser& p_;
    pugi::xml_node node_;
    std::uint64_t count_ = 0, index_ = 0;
    VtkDataType type_;
    std::optional<ChunkedFile> text_;  // ascii
    // binary: the decoded block, its size, the data's size and how much was handed out
    std::optional<ByteStream> bytes_;
    std::uint64_t present_ = 0, want_ = 0, consumed_ = 0;
    std::string buffer_;
    std::size_t pos_ = 0;
    // compressed: the header, the block being inflated
    std::uint64_t size_ = 0, last_size_ = 0, blocks_ = 0, position_ = 0;
    std::vector<std::uint64_t> compressed_sizes_;
    std::size_t block_ = 0;
    std::uint64_t in_left_ = 0, out_left_ = 0, expected_ = 0;
    bool inflating_ = false;
    z_stream z_{};
    std::string compressed_, window_;
    std::size_t window_pos_ = 0;
  };

  // The first pass: copies the markup to m_.xml without the arrays' text, up to <AppendedData>
  // (which ends it, as ReadVtu cuts the file there); false for a CDATA section.
  bool ScanMarkup() {
    std::string tag;        // the markup being read, from its '<'
    bool in_tag = false;    // inside markup
    char quote = 0;         // inside a quoted attribute value
    int array_depth = -1;   // elements open inside the current <DataArray>; -1: none open
    std::uint64_t run = 0;  // where the current text run began
    bool run_text = false;  // the run has a character that is not blank
    // An array's own text run goes into the markup as its line breaks and a '0' after the last
    // line break before its last character that is not blank: the parser then sees text there,
    // as in the file, and names the lines the file has (at the file's end too).
    // A blank other than a line break after the last line break ends it with a space too.
    std::size_t lines_before = 0, lines_after = 0;
    char run_last = 0;
    auto end_run = [&] {
      m_.xml.append(lines_before, '\n');
      if (run_text) m_.xml += '0';
      m_.xml.append(lines_after, '\n');
      if (lines_after > 0 && run_last != '\n' && internal::IsBlankByte(run_last)) m_.xml += ' ';
      lines_before = lines_after = 0;
      run_text = false;
      run_last = 0;
    };
    for (std::string_view piece = file_.Take(internal::kChunk); !piece.empty();
         piece = file_.Take(internal::kChunk)) {
      const std::uint64_t at = file_.offset() - piece.size();
      std::size_t i = 0;
      while (i < piece.size()) {
        if (!in_tag) {
          const std::size_t lt = std::min(piece.find('<', i), piece.size());
          std::string_view text = piece.substr(i, lt - i);
          if (array_depth == 0) {  // counted, and written where the run ends
            const auto last = std::find_if(text.rbegin(), text.rend(), [](char c) {
                                return !internal::IsBlankByte(c);
                              }).base();
            if (last != text.begin()) {
              run_text = true;
              lines_before += lines_after + Lines(text.substr(0, last - text.begin()));
              lines_after = 0;
            }
            lines_after += Lines(text.substr(last - text.begin()));
            if (!text.empty()) run_last = text.back();
          } else {
            m_.xml.append(text);
          }
          i = lt;
          if (i < piece.size()) {
            if (array_depth == 0 && run_text && !m_.texts.back().found)
              m_.texts.back() = {run, at + i, true};
            end_run();
            in_tag = true;
            tag.clear();
          }
          continue;
        }
        // Inside markup: find its end.
        std::size_t j = i;
        bool closed = false;
        for (; j < piece.size() && !closed; ++j) {
          const char c = piece[j];
          tag += c;
          if (tag.size() == 4 && tag == "<!--") quote = '-';  // a comment: ends at "-->"
          if (tag.size() == 9 && tag == "<![CDATA[") return false;
          if (quote == '-') {
            closed = tag.size() >= 7 && tag.compare(tag.size() - 3, 3, "-->") == 0;
          } else if (quote != 0) {
            if (c == quote) quote = 0;
          } else if (c == '"' || c == '\'') {
            quote = c;
          } else if (c == '>') {
            closed = true;
          }
          if (tag.size() == 13 && tag == "<AppendedData") {
            Appended(at + j + 1 - tag.size());
            return true;
          }
          if (tag.size() > internal::kLongest)
            ThrowInputError(source_, fmt::format("line {}", LinesIn(m_.xml) + 1),
                            "markup longer than 64 MiB");
        }
        i = j;
        if (!closed) continue;
        in_tag = false;
        quote = 0;
        m_.xml += tag;
        run = at + i;
        run_text = false;
        if (tag.size() < 2 || tag[1] == '!' || tag[1] == '?') continue;
        const bool end_tag = tag[1] == '/';
        const bool empty = tag[tag.size() - 2] == '/';
        if (end_tag) {
          if (array_depth > 0)
            --array_depth;
          else if (array_depth == 0)
            array_depth = -1;
          continue;
        }
        if (array_depth >= 0) {
          if (!empty) ++array_depth;
          continue;
        }
        std::size_t name_end = 1;
        while (name_end < tag.size() && !internal::IsBlankByte(tag[name_end]) &&
               tag[name_end] != '>' && tag[name_end] != '/')
          ++name_end;
        if (std::string_view(tag).substr(1, name_end - 1) == "DataArray") {
          m_.texts.emplace_back();
          if (!empty) array_depth = 0;
        }
      }
    }
    if (in_tag) m_.xml += tag;  // a file that ends inside markup: the parser names it
    end_run();
    return true;
  }

  // <AppendedData> at file offset `at`: where its data begins ('_') and ends, as ReadVtu finds
  // them. The markup ends before it.
  void Appended(std::uint64_t at) {
    m_.appended_line = LinesIn(m_.xml) + 1;
    m_.xml += "</VTKFile>";
    file_.Seek(at, file_.size());
    std::string tag;
    bool closed = false;
    while (!closed && tag.size() <= internal::kLongest) {
      const std::string_view piece = file_.Take(kPiece);
      if (piece.empty()) break;
      const std::size_t gt = piece.find('>');
      closed = gt != std::string_view::npos;
      tag.append(piece.substr(0, closed ? gt : piece.size()));
    }
    if (closed) file_.Seek(at + tag.size() + 1, file_.size());
    if (!closed || !file_.SkipPast("_"))
      ThrowInputError(source_, fmt::format("line {}", m_.appended_line),
                      "expected '_' starting the <AppendedData> content");
    m_.appended = true;
    m_.appended_base64 = tag.find("encoding=\"base64\"") != std::string::npos;
    m_.appended_begin = file_.offset();
    m_.appended_end = file_.size();
    if (m_.appended_base64 && file_.SkipPast("<")) m_.appended_end = file_.offset() - 1;
  }

  // Numbers the parsed <DataArray> elements in document order, as the first pass met them
  // (walking the tree without recursion: a file may nest deeply).
  void NumberArrays(const pugi::xml_document& doc) {
    std::size_t next = 0;
    pugi::xml_node node = doc.first_child();
    while (node) {
      if (node.type() == pugi::node_element && std::string_view(node.name()) == "DataArray")
        array_index_[node.internal_object()] = next++;
      if (node.first_child()) {
        node = node.first_child();
        continue;
      }
      while (node && node != doc && !node.next_sibling()) node = node.parent();
      node = node && node != doc ? node.next_sibling() : pugi::xml_node();
    }
  }
  const ArrayText& TextOf(const pugi::xml_node& node) const {
    static const ArrayText kNone;
    auto it = array_index_.find(node.internal_object());
    if (it == array_index_.end() || it->second >= m_.texts.size()) return kNone;
    return m_.texts[it->second];
  }

  [[noreturn]] void Fail(const pugi::xml_node& node, std::string_view what) const {
    markup_.Fail(node, what);
  }
  std::uint64_t Attribute(const pugi::xml_node& node, const char* name) const {
    return markup_.Attribute(node, name);
  }

  // ReadVtu's ReadPiece for the only piece, keeping the block; false for quadratic cells.
  bool ReadPiece(const pugi::xml_node& piece) {
    const std::uint64_t num_points = Attribute(piece, "NumberOfPoints");
    const std::uint64_t num_cells = Attribute(piece, "NumberOfCells");
    if (num_points > static_cast<std::uint64_t>(std::numeric_limits<int>::max()))
      Fail(piece, "too many points");
    pugi::xml_node points = markup_.PointsArray(piece);
    const auto nodes = static_cast<std::int64_t>(num_points);
    const std::int64_t node_begin = BlockBegin(nodes, rank_, size_);
    const std::int64_t node_end = BlockBegin(nodes, rank_ + 1, size_);
    Points kept(3, static_cast<Index>(node_end - node_begin));
    {
      Array xyz(*this, points, 3 * num_points, false);
      for (std::int64_t n = 0; n < nodes; ++n)
        for (int a = 0; a < 3; ++a) {
          const double v = xyz.NextReal();
          if (n >= node_begin && n < node_end) kept(a, static_cast<Index>(n - node_begin)) = v;
        }
    }
    std::int64_t tets = 0, triangles = 0, connectivity = 0;
    pugi::xml_node cells, offsets_node, types_node, conn_node;
    if (num_cells > 0) {
      cells = piece.child("Cells");
      if (!cells) Fail(piece, "expected a <Cells> element");
      offsets_node = markup_.FindArray(cells, "offsets");
      types_node = markup_.FindArray(cells, "types");
      conn_node = markup_.FindArray(cells, "connectivity");
      {  // ReadVtu reads the offsets whole before it opens the types
        Array offsets(*this, offsets_node, num_cells, true);
        for (std::uint64_t c = 0; c < num_cells; ++c) {
          const std::int64_t offset = offsets.NextInt();
          if (offset < connectivity)
            Fail(offsets_node, fmt::format("offset {} of cell {} is below the previous {}", offset,
                                           c, connectivity));
          connectivity = offset;
        }
      }
      {
        Array types(*this, types_node, num_cells, true);
        for (std::uint64_t c = 0; c < num_cells; ++c) {
          const std::int64_t type = types.NextInt();
          if (type == 24 || type == 22) return false;
          tets += type == 10;
          triangles += type == 5;
        }
      }
    }
    const internal::BlockRanges r =
        internal::StartBlock(block_, rank_, size_, nodes, tets, triangles, file_);
    block_.nodes = std::move(kept);
    if (num_cells == 0) return true;
    Array offsets(*this, offsets_node, num_cells, true);
    Array types(*this, types_node, num_cells, true);
    Array conn(*this, conn_node, static_cast<std::uint64_t>(connectivity), true);
    std::int64_t begin = 0, tet = 0, triangle = 0;
    for (std::uint64_t c = 0; c < num_cells; ++c) {
      const std::int64_t end = offsets.NextInt();
      const std::int64_t k = end - begin;
      begin = end;
      const std::int64_t type = types.NextInt();
      if (type != 10 && type != 5) {
        for (std::int64_t a = 0; a < k; ++a) (void)conn.NextInt();
        continue;
      }
      const bool is_tet = type == 10;
      const std::int64_t want = is_tet ? 4 : 3;
      if (k != want)
        Fail(conn_node, fmt::format("expected {} point indices for a {} (cell {}), got {}", want,
                                    is_tet ? "tetrahedron" : "triangle", c, k));
      Index idx[4];
      for (std::int64_t a = 0; a < k; ++a) {
        const std::int64_t p = conn.NextInt();
        if (p < 0 || static_cast<std::uint64_t>(p) >= num_points)
          Fail(conn_node,
               fmt::format("cell {} refers to point {}, out of range [0, {})", c, p, num_points));
        idx[a] = static_cast<Index>(p);
        for (std::int64_t c2 = 0; c2 < a; ++c2)
          if (idx[c2] == idx[a]) Fail(conn_node, fmt::format("cell {} repeats point {}", c, p));
      }
      if (is_tet) {
        if (tet >= r.tet_begin && tet < r.tet_end)
          for (int a = 0; a < 4; ++a)
            block_.tets(a, static_cast<Index>(tet - r.tet_begin)) = idx[a];
        ++tet;
      } else {
        if (triangle >= r.triangle_begin && triangle < r.triangle_end)
          for (int a = 0; a < 3; ++a)
            block_.triangles(a, static_cast<Index>(triangle - r.triangle_begin)) = idx[a];
        ++triangle;
      }
    }
    return true;
  }

  std::filesystem::path path_;
  std::string source_;
  ChunkedFile file_;
  int rank_, size_;
  Markup m_;
  internal::VtuMarkup markup_;  // messages: lines counted in m_.xml
  std::unordered_map<const void*, std::size_t> array_index_;
  bool swap_ = false, compressed_ = false;
  int header_bytes_ = 4;
  MeshBlock block_;
};

}  // namespace

std::optional<MeshBlock> ReadVtuBlock(const std::filesystem::path& path, int rank, int size) {
  return VtuBlockParser(path, rank, size).Read();
}

}  // namespace gipsi
