#pragma once
/// @file
/// Internal helper of the mesh readers that read one process's block of a mesh without holding
/// the file (gmsh_block_reader.h, tetgen_reader.h, vtk_legacy_reader.h): a file read front to
/// back through a buffer of about 1 MiB, handing out lines, tokens and raw bytes with the line
/// number and byte offset that messages name, as internal::TextReader does for a file held
/// whole; and the ranges of a block's items. Not part of the public API.

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <string>
#include <string_view>

#include <fmt/format.h>

#include "gipsi/base/error.h"
#include "gipsi/geometry/mesh_block.h"
#include "gipsi/io/text_reader.h"

namespace gipsi::internal {

constexpr std::size_t kChunk = std::size_t{1} << 20;    // bytes read at a time
constexpr std::size_t kLongest = std::size_t{1} << 26;  // longest line or token held

inline bool IsBlankByte(char c) {
  return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\v' || c == '\f';
}

/// A file read front to back through a buffer of about kChunk bytes, handing out lines,
/// tokens and raw bytes (valid until the next call), with the line number and byte offset
/// for messages as internal::TextReader gives them.
class ChunkedFile {
 public:
  // Opens the file as ReadFileBytes does: a directory or a device is refused by name.
  explicit ChunkedFile(const std::filesystem::path& path) : source_(path.string()) {
    auto fail = [&](const std::string& what) {
      throw InputError(fmt::format("{}: {}", source_, what));
    };
    // O_NONBLOCK: opening a FIFO must not wait for a writer; regular files ignore it.
    fd_ = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK);
    struct stat info {};
    if (fd_ < 0 || ::fstat(fd_, &info) != 0)
      fail(fmt::format("cannot open mesh file for reading: {}", std::strerror(errno)));
    if (S_ISDIR(info.st_mode)) fail("is a directory, expected a mesh file");
    if (!S_ISREG(info.st_mode))
      fail("is not a regular file (a device, pipe or socket), expected a mesh file");
    size_ = limit_ = static_cast<std::uint64_t>(info.st_size);
    // A small file needs no more than itself (and one byte to see its end).
    buffer_.resize(static_cast<std::size_t>(std::min<std::uint64_t>(kChunk, size_ + 1)));
  }
  ~ChunkedFile() {
    if (fd_ >= 0) ::close(fd_);
  }
  ChunkedFile(const ChunkedFile&) = delete;
  ChunkedFile& operator=(const ChunkedFile&) = delete;

  void Rewind() {
    if (::lseek(fd_, 0, SEEK_SET) != 0)
      ThrowInputError(source_, "", fmt::format("cannot read mesh file: {}", std::strerror(errno)));
    begin_ = end_ = 0;
    base_ = 0;
    limit_ = size_;
    line_ = last_line_ = 1;
    eof_ = false;
  }
  /// Reads on from byte `begin` as if the file ended at byte `end` (at most its size). The line
  /// count restarts at 1: messages about what follows name the offset or their own place.
  void Seek(std::uint64_t begin, std::uint64_t end) {
    limit_ = std::min(end, size_);
    begin = std::min(begin, limit_);
    if (::lseek(fd_, static_cast<off_t>(begin), SEEK_SET) != static_cast<off_t>(begin))
      ThrowInputError(source_, "", fmt::format("cannot read mesh file: {}", std::strerror(errno)));
    begin_ = end_ = 0;
    base_ = begin;
    line_ = last_line_ = 1;
    eof_ = begin == limit_;
  }
  [[nodiscard]] std::uint64_t offset() const { return base_ + begin_; }
  [[nodiscard]] std::uint64_t remaining() const { return limit_ - offset(); }
  [[nodiscard]] std::uint64_t size() const { return size_; }
  /// The next bytes, at most `max` and at least one before the end (empty there), consumed
  /// without counting their lines: for binary data, or text whose lines the caller counts.
  std::string_view Take(std::size_t max) {
    if (begin_ == end_) Fill(1);
    const std::size_t n = std::min(max, end_ - begin_);
    std::string_view bytes(buffer_.data() + begin_, n);
    begin_ += n;
    return bytes;
  }

  bool NextLine(std::string_view* out) {
    for (;;) {
      const char* start = buffer_.data() + begin_;
      const auto* newline = static_cast<const char*>(std::memchr(start, '\n', end_ - begin_));
      if (newline != nullptr || (eof_ && begin_ < end_)) {
        const auto length =
            newline != nullptr ? static_cast<std::size_t>(newline - start) : end_ - begin_;
        std::string_view text(start, length);
        if (!text.empty() && text.back() == '\r') text.remove_suffix(1);
        *out = text;
        last_line_ = line_;
        begin_ += newline != nullptr ? length + 1 : length;
        if (newline != nullptr) ++line_;
        return true;
      }
      if (eof_) return false;
      Fill(end_ - begin_ + 1);
    }
  }
  /// The next non-blank line, trimmed; false at the end.
  bool NextContentLine(std::string_view* out) {
    std::string_view text;
    while (NextLine(&text)) {
      text = internal::Trim(text);
      if (!text.empty()) {
        *out = text;
        return true;
      }
    }
    return false;
  }
  std::string_view RequireContentLine(std::string_view what) {
    std::string_view text;
    if (!NextContentLine(&text)) Fail(fmt::format("expected {}, got end of file", what));
    return text;
  }
  /// The next line with something left once everything from `comment` on is removed, trimmed;
  /// at the end of the file, InputError `line N: expected <what>, got end of file` (N the line
  /// after the last), as TextReader::RequireContentLine.
  std::string_view RequireContentLine(std::string_view what, char comment) {
    std::string_view text;
    while (NextLine(&text)) {
      const std::size_t c = text.find(comment);
      if (c != std::string_view::npos) text = text.substr(0, c);
      text = internal::Trim(text);
      if (!text.empty()) return text;
    }
    last_line_ = line_;
    Fail(fmt::format("expected {}, got end of file", what));
  }
  /// As TextReader::CheckCount: InputError unless `count` items of at least `min_bytes_each`
  /// bytes fit in the rest of the file.
  void CheckCount(std::int64_t count, std::size_t min_bytes_each, std::string_view what) const {
    if (count < 0) Fail(fmt::format("expected a non-negative number of {}, got {}", what, count));
    const std::size_t each = std::max<std::size_t>(min_bytes_each, 1);
    if (static_cast<std::uint64_t>(count) > remaining() / each)
      Fail(
          fmt::format("declares {} {}, but only {} bytes remain in the file (truncated file or "
                      "wrong count?)",
                      count, what, remaining()));
  }
  /// As TextReader::ToInt and ToFinite, naming the line of the last item handed out.
  std::int64_t ToInt(std::string_view token, std::string_view what) const {
    std::int64_t value = 0;
    if (!TryParseInt(token, &value)) Fail(fmt::format("expected {}, got {}", what, Quote(token)));
    return value;
  }
  double ToFinite(std::string_view token, std::string_view what) const {
    double value = 0;
    if (!TryParseDouble(token, &value) || !std::isfinite(value))
      Fail(fmt::format("expected {} (a finite number), got {}", what, Quote(token)));
    return value;
  }
  [[nodiscard]] const std::string& source() const { return source_; }
  /// The line of the last item handed out, which messages name.
  [[nodiscard]] int line() const { return last_line_; }
  std::string_view Token(std::string_view what) {
    std::string_view token;
    if (!TryToken(&token)) Fail(fmt::format("expected {}, got end of file", what));
    return token;
  }
  /// The next token, as Token; false at the end of the file.
  bool TryToken(std::string_view* out) {
    for (;;) {
      while (begin_ < end_ && IsBlankByte(buffer_[begin_])) {
        if (buffer_[begin_] == '\n') ++line_;
        ++begin_;
      }
      if (begin_ < end_ || eof_) break;
      Fill(1);
    }
    last_line_ = line_;
    std::size_t k = begin_;
    for (;;) {
      while (k < end_ && !IsBlankByte(buffer_[k])) ++k;
      if (k < end_ || eof_) break;
      const std::size_t held = k - begin_;
      Fill(held + 1);
      k = begin_ + held;
    }
    if (k == begin_) return false;
    *out = std::string_view(buffer_.data() + begin_, k - begin_);
    begin_ = k;
    return true;
  }
  /// Whether the next token is `word` (letters compared case-insensitively), consuming nothing:
  /// binary data may follow a header line, so only the bytes of `word` and one more are looked at.
  bool NextTokenIs(std::string_view word) {
    std::size_t k = 0;  // from begin_: the first byte that is not blank
    for (;;) {
      while (begin_ + k < end_ && IsBlankByte(buffer_[begin_ + k])) ++k;
      if (eof_ || (begin_ + k < end_ && end_ - begin_ - k > word.size())) break;
      Fill(k + word.size() + 1);
    }
    const std::size_t held = end_ - begin_ - k;
    if (held < word.size()) return false;
    for (std::size_t i = 0; i < word.size(); ++i)
      if (std::tolower(static_cast<unsigned char>(buffer_[begin_ + k + i])) !=
          std::tolower(static_cast<unsigned char>(word[i])))
        return false;
    return held == word.size() || IsBlankByte(buffer_[begin_ + k + word.size()]);
  }
  /// Consumes the rest of the current line and its line break (the line of the last item
  /// handed out stays the one messages name).
  void SkipRestOfLine() {
    std::string_view ignored;
    const int keep = last_line_;
    (void)NextLine(&ignored);
    last_line_ = keep;
  }
  std::string_view Bytes(std::size_t n, std::string_view what) {
    if (end_ - begin_ < n) Fill(n);
    if (end_ - begin_ < n)
      FailAtOffset(fmt::format("expected {} ({} bytes), only {} remain", what, n, end_ - begin_));
    std::string_view bytes(buffer_.data() + begin_, n);
    Consume(n);
    return bytes;
  }
  void Skip(std::uint64_t n, std::string_view what) {
    while (n > 0) {
      const auto part = static_cast<std::size_t>(std::min<std::uint64_t>(n, kChunk));
      (void)Bytes(part, what);
      n -= part;
    }
  }
  /// Moves past the next occurrence of `marker`; false if there is none.
  bool SkipPast(std::string_view marker) {
    for (;;) {
      const std::string_view held(buffer_.data() + begin_, end_ - begin_);
      const std::size_t at = held.find(marker);
      if (at != std::string_view::npos) {
        Consume(at + marker.size());
        return true;
      }
      if (eof_) return false;
      const std::size_t keep = std::min(held.size(), marker.size() - 1);
      Consume(held.size() - keep);
      Fill(keep + 1);
    }
  }

  [[noreturn]] void Fail(std::string_view what) const {
    ThrowInputError(source_, fmt::format("line {}", last_line_), what);
  }
  [[noreturn]] void FailAtOffset(std::string_view what) const { FailAtOffset(what, offset()); }
  [[noreturn]] void FailAtOffset(std::string_view what, std::uint64_t at) const {
    ThrowInputError(source_, fmt::format("byte offset {}", at), what);
  }

 private:
  void Consume(std::size_t n) {
    line_ +=
        static_cast<int>(std::count(buffer_.data() + begin_, buffer_.data() + begin_ + n, '\n'));
    begin_ += n;
  }
  // Keeps the unread bytes and reads until `need` of them are held or the file ends.
  void Fill(std::size_t need) {
    if (begin_ > 0) {
      std::memmove(buffer_.data(), buffer_.data() + begin_, end_ - begin_);
      base_ += begin_;
      end_ -= begin_;
      begin_ = 0;
    }
    if (need > buffer_.size()) {
      if (need > kLongest)
        FailAtOffset(fmt::format("a line or value longer than {} bytes", kLongest));
      buffer_.resize(std::max(need, 2 * buffer_.size()));
    }
    while (end_ < need && !eof_) {
      const std::uint64_t room =
          std::min<std::uint64_t>(buffer_.size() - end_, limit_ - base_ - end_);
      const ssize_t got = room == 0 ? 0 : ::read(fd_, buffer_.data() + end_, room);
      if (got < 0 && errno == EINTR) continue;
      if (got < 0)
        ThrowInputError(source_, "",
                        fmt::format("cannot read mesh file: {}", std::strerror(errno)));
      end_ += static_cast<std::size_t>(got);
      if (got == 0) eof_ = true;
    }
  }

  std::string source_;
  int fd_ = -1;
  std::uint64_t size_ = 0, limit_ = 0;  // the file's size; where reading stops (Seek)
  std::string buffer_;
  std::size_t begin_ = 0, end_ = 0;  // the unread bytes held
  std::uint64_t base_ = 0;           // file offset of buffer_[0]
  int line_ = 1, last_line_ = 1;
  bool eof_ = false;
};

/// The whole-mesh indices of a block's nodes, tets and triangles: [begin, end) each.
struct BlockRanges {
  std::int64_t node_begin = 0, node_end = 0, tet_begin = 0, tet_end = 0;
  std::int64_t triangle_begin = 0, triangle_end = 0;
};

/// Sets `block`'s counts of the whole mesh and sizes its nodes, tets and triangles for its
/// rank's share of them; returns the ranges it holds. Refuses (through `file`, naming its last
/// line) more than 2^31 - 1 tets or triangles.
inline BlockRanges StartBlock(MeshBlock& block, int rank, int size, std::int64_t nodes,
                              std::int64_t tets, std::int64_t triangles, const ChunkedFile& file) {
  if (tets > INT32_MAX || triangles > INT32_MAX)
    file.Fail(fmt::format("{} tets and {} triangles: more than 2^31 - 1", tets, triangles));
  block.rank = rank;
  block.size = size;
  block.num_nodes = nodes;
  block.num_tets = tets;
  block.num_triangles = triangles;
  BlockRanges r;
  r.node_begin = BlockBegin(nodes, rank, size);
  r.node_end = BlockBegin(nodes, rank + 1, size);
  r.tet_begin = BlockBegin(tets, rank, size);
  r.tet_end = BlockBegin(tets, rank + 1, size);
  r.triangle_begin = BlockBegin(triangles, rank, size);
  r.triangle_end = BlockBegin(triangles, rank + 1, size);
  block.first_triangle = r.triangle_begin;
  block.nodes.resize(3, static_cast<Index>(r.node_end - r.node_begin));
  block.tets.resize(4, static_cast<Index>(r.tet_end - r.tet_begin));
  block.triangles.resize(3, static_cast<Index>(r.triangle_end - r.triangle_begin));
  return r;
}

}  // namespace gipsi::internal
