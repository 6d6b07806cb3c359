#pragma once
/// @file
/// Internal helpers shared by the mesh readers: a cursor over a whole file held in memory that
/// hands out lines, whitespace-separated tokens and raw bytes while keeping track of the line
/// number and byte offset, so that every error can name where it happened; number parsing with
/// messages; byte-order helpers; a vertex/node tag map. Not part of the public API.

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <string>
#include <string_view>
#include <unordered_map>
#include <vector>

#include "gipsi/base/export.h"

GIPSI_EXPORT_BEGIN
namespace gipsi::internal {

/// Reads the whole file at `path` as bytes. Throws InputError `PATH: cannot open file` when it
/// cannot be opened or read.
std::string ReadFileBytes(const std::filesystem::path& path);

/// Writes `bytes` to `path` atomically (gipsi::WriteFileAtomically); throws OutputError.
void WriteFileBytes(const std::filesystem::path& path, std::string_view bytes);

/// Writes `bytes` to `PATH.tmp` and renames it to `path`, so that readers of `path` only ever
/// see a complete file (the old or the new one). Throws OutputError (with errno text).
void WriteFileAtomically(const std::filesystem::path& path, std::string_view bytes);

/// A printable, length-limited rendering of a token for error messages (non-printable bytes
/// become `\xNN`, long tokens are cut with `...`).
std::string Quote(std::string_view token);

/// Splits `line` at blanks (space, tab, CR, LF, vertical tab, form feed).
std::vector<std::string_view> SplitTokens(std::string_view line);

/// `s` without leading and trailing blanks.
std::string_view Trim(std::string_view s);

/// Parses an integer (optionally signed, whole token). Returns false on any trailing junk.
bool TryParseInt(std::string_view token, std::int64_t* out);

/// Parses a floating-point number (whole token; accepts a leading '+', `nan`, `inf`).
bool TryParseDouble(std::string_view token, double* out);

/// A read cursor over the bytes of one file. Tracks the 1-based line number of the last item
/// handed out and the byte offset of the cursor. Every `Require*`/`To*` method throws InputError
/// with `SOURCE: line N: expected ..., got ...` on failure; binary reads use byte offsets.
/// Movable, not copyable (it owns the file contents).
class TextReader {
 public:
  /// `source` names the file in messages (usually the path); `data` is the whole file.
  TextReader(std::string source, std::string data);
  /// Reads the whole file (throws InputError `cannot open file`).
  static TextReader FromFile(const std::filesystem::path& path);

  TextReader(const TextReader&) = delete;
  TextReader& operator=(const TextReader&) = delete;
  TextReader(TextReader&&) = default;
  TextReader& operator=(TextReader&&) = default;

  [[nodiscard]] const std::string& source() const { return source_; }
  [[nodiscard]] std::string_view data() const { return data_; }
  /// Line number (1-based) of the last line or token handed out.
  [[nodiscard]] int line() const { return last_line_; }
  /// Byte offset of the cursor.
  [[nodiscard]] std::size_t offset() const { return pos_; }
  [[nodiscard]] std::size_t remaining() const { return data_.size() - pos_; }
  [[nodiscard]] bool AtEnd() const { return pos_ >= data_.size(); }

  /// Hands out the next line (without its CR/LF). Returns false at end of data.
  bool NextLine(std::string_view* line);
  /// The next line that is not blank (and, if `comment` is non-zero, with everything from
  /// `comment` on removed), trimmed. Throws `expected <what>, got end of file` at the end.
  std::string_view RequireContentLine(std::string_view what, char comment = '\0');
  /// Like RequireContentLine but returns false at the end instead of throwing.
  bool NextContentLine(std::string_view* line, char comment = '\0');

  /// Skips blanks (counting lines) and returns the next token; empty at end of data.
  std::string_view NextToken();
  /// The next token or throws `expected <what>, got end of file`.
  std::string_view RequireToken(std::string_view what);
  /// The next token without consuming anything (empty at end).
  [[nodiscard]] std::string_view PeekToken() const;
  /// Consumes the rest of the current line including its line break.
  void SkipRestOfLine();

  /// Hands out the next `n` raw bytes. Throws `byte offset X: expected <what> (n bytes), only R
  /// remain` when the file is too short.
  std::string_view ReadBytes(std::size_t n, std::string_view what);
  /// Moves the cursor to `offset` (<= size), recomputing the line number.
  void Seek(std::size_t offset);

  /// Throws InputError unless `count` items of at least `min_bytes_each` bytes fit in the rest
  /// of the file (guards allocations sized by counts declared in headers).
  void CheckCount(std::int64_t count, std::size_t min_bytes_each, std::string_view what) const;

  /// Parses `token` as an integer or throws `line N: expected <what>, got 'token'`.
  [[nodiscard]] std::int64_t ToInt(std::string_view token, std::string_view what) const;
  /// Parses `token` as a finite number or throws `line N: expected <what>, got 'token'`.
  [[nodiscard]] double ToFinite(std::string_view token, std::string_view what) const;
  /// RequireToken + ToInt / ToFinite.
  std::int64_t ReadInt(std::string_view what) { return ToInt(RequireToken(what), what); }
  double ReadFinite(std::string_view what) { return ToFinite(RequireToken(what), what); }

  /// Throws InputError `SOURCE: line N: what`.
  [[noreturn]] void Fail(std::string_view what) const;
  /// Throws InputError `SOURCE: byte offset X: what` (X is the cursor unless given).
  [[noreturn]] void FailAtOffset(std::string_view what, std::size_t offset) const;
  [[noreturn]] void FailAtOffset(std::string_view what) const { FailAtOffset(what, pos_); }

 private:
  void SkipBlanks();
  void Advance(std::size_t n);

  std::string source_;
  std::string data_;
  std::size_t pos_ = 0;
  int current_line_ = 1;  // line of the cursor
  int last_line_ = 1;     // line of the last item handed out
};

/// True on little-endian hosts.
inline bool HostIsLittleEndian() {
  const std::uint16_t one = 1;
  unsigned char first = 0;
  std::memcpy(&first, &one, 1);
  return first == 1;
}

/// Loads a `T` (trivially copyable) from `bytes`, swapping its bytes if `swap`.
template <class T>
T LoadScalar(const char* bytes, bool swap) {
  char buf[sizeof(T)];
  std::memcpy(buf, bytes, sizeof(T));
  if (swap)
    for (std::size_t i = 0; i < sizeof(T) / 2; ++i) std::swap(buf[i], buf[sizeof(T) - 1 - i]);
  T value;
  std::memcpy(&value, buf, sizeof(T));
  return value;
}

/// Maps file-specific node tags (any integers) to dense indices 0..N-1 in insertion order.
class TagMap {
 public:
  void Reserve(std::size_t n) { map_.reserve(n); }
  /// Adds `tag` as the next index; returns false if it was already present.
  bool Insert(std::int64_t tag) { return map_.emplace(tag, static_cast<int>(map_.size())).second; }
  /// The index of `tag`, or -1.
  [[nodiscard]] int Find(std::int64_t tag) const {
    auto it = map_.find(tag);
    return it == map_.end() ? -1 : it->second;
  }
  [[nodiscard]] std::size_t size() const { return map_.size(); }

 private:
  std::unordered_map<std::int64_t, int> map_;
};

}  // namespace gipsi::internal
GIPSI_EXPORT_END
