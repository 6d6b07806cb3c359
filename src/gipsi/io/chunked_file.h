#pragma once
/// @file
/// Internal helper of the mesh readers that read one process's block of a mesh without holding
/// the file (gmsh_block_reader.h, tetgen_reader.h): a file read front to back through a buffer
/// of about 1 MiB, handing out lines, tokens and raw bytes with the line number and byte offset
/// that messages name, as internal::TextReader does for a file held whole. Not part of the
/// public API.

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <string>
#include <string_view>

#include <fmt/format.h>

#include "gipsi/base/error.h"
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
    size_ = static_cast<std::uint64_t>(info.st_size);
    buffer_.resize(kChunk);
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
    line_ = last_line_ = 1;
    eof_ = false;
  }
  [[nodiscard]] std::uint64_t offset() const { return base_ + begin_; }
  [[nodiscard]] std::uint64_t remaining() const { return size_ - offset(); }

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
  std::string_view Token(std::string_view what) {
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
    if (k == begin_) Fail(fmt::format("expected {}, got end of file", what));
    std::string_view token(buffer_.data() + begin_, k - begin_);
    begin_ = k;
    return token;
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
  [[noreturn]] void FailAtOffset(std::string_view what) const {
    ThrowInputError(source_, fmt::format("byte offset {}", offset()), what);
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
      const ssize_t got = ::read(fd_, buffer_.data() + end_, buffer_.size() - end_);
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
  std::uint64_t size_ = 0;
  std::string buffer_;
  std::size_t begin_ = 0, end_ = 0;  // the unread bytes held
  std::uint64_t base_ = 0;           // file offset of buffer_[0]
  int line_ = 1, last_line_ = 1;
  bool eof_ = false;
};

}  // namespace gipsi::internal
