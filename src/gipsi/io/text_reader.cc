#include "gipsi/io/text_reader.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <fstream>
#include <iterator>
#include <limits>

#include <fmt/format.h>

#include "gipsi/base/error.h"
#include "gipsi/base/file_io.h"

namespace gipsi::internal {
namespace {

bool IsBlank(char c) {
  return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\v' || c == '\f';
}

}  // namespace

std::string ReadFileBytes(const std::filesystem::path& path) {
  // A mesh may be large, but it must be a regular file: a device (/dev/zero) or a directory is
  // refused by name instead of read without end or failing inside the stream library.
  return ReadRegularFile(path, std::numeric_limits<std::uintmax_t>::max(), "mesh file");
}

void WriteFileBytes(const std::filesystem::path& path, std::string_view bytes) {
  gipsi::WriteFileAtomically(path, bytes);
}

void WriteFileAtomically(const std::filesystem::path& path, std::string_view bytes) {
  gipsi::WriteFileAtomically(path, bytes);
}

std::string Quote(std::string_view token) {
  constexpr std::size_t kMax = 32;
  std::string out = "'";
  for (std::size_t i = 0; i < token.size() && i < kMax; ++i) {
    auto c = static_cast<unsigned char>(token[i]);
    if (c >= 32 && c < 127)
      out += static_cast<char>(c);
    else
      out += fmt::format("\\x{:02x}", c);
  }
  if (token.size() > kMax) out += "...";
  out += "'";
  return out;
}

std::vector<std::string_view> SplitTokens(std::string_view line) {
  std::vector<std::string_view> tokens;
  std::size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && IsBlank(line[i])) ++i;
    std::size_t start = i;
    while (i < line.size() && !IsBlank(line[i])) ++i;
    if (i > start) tokens.push_back(line.substr(start, i - start));
  }
  return tokens;
}

std::string_view Trim(std::string_view s) {
  while (!s.empty() && IsBlank(s.front())) s.remove_prefix(1);
  while (!s.empty() && IsBlank(s.back())) s.remove_suffix(1);
  return s;
}

bool TryParseInt(std::string_view token, std::int64_t* out) {
  if (!token.empty() && token.front() == '+') token.remove_prefix(1);
  if (token.empty()) return false;
  const char* end = token.data() + token.size();
  auto [ptr, ec] = std::from_chars(token.data(), end, *out);
  return ec == std::errc() && ptr == end;
}

bool TryParseDouble(std::string_view token, double* out) {
  if (!token.empty() && token.front() == '+') token.remove_prefix(1);
  if (token.empty()) return false;
  const char* end = token.data() + token.size();
  auto [ptr, ec] = std::from_chars(token.data(), end, *out);
  if (ec == std::errc::result_out_of_range) {
    *out = HUGE_VAL;  // treated as non-finite by callers
    return ptr == end;
  }
  return ec == std::errc() && ptr == end;
}

TextReader::TextReader(std::string source, std::string data)
    : source_(std::move(source)), data_(std::move(data)) {}

TextReader TextReader::FromFile(const std::filesystem::path& path) {
  return TextReader(path.string(), ReadFileBytes(path));
}

void TextReader::Advance(std::size_t n) {
  n = std::min(n, data_.size() - pos_);
  current_line_ +=
      static_cast<int>(std::count(data_.begin() + static_cast<std::ptrdiff_t>(pos_),
                                  data_.begin() + static_cast<std::ptrdiff_t>(pos_ + n), '\n'));
  pos_ += n;
}

bool TextReader::NextLine(std::string_view* line) {
  if (AtEnd()) return false;
  last_line_ = current_line_;
  std::size_t end = data_.find('\n', pos_);
  std::size_t stop = end == std::string::npos ? data_.size() : end;
  std::string_view text(data_.data() + pos_, stop - pos_);
  if (!text.empty() && text.back() == '\r') text.remove_suffix(1);
  *line = text;
  pos_ = end == std::string::npos ? data_.size() : end + 1;
  if (end != std::string::npos) ++current_line_;
  return true;
}

bool TextReader::NextContentLine(std::string_view* line, char comment) {
  std::string_view text;
  while (NextLine(&text)) {
    if (comment != '\0') {
      std::size_t c = text.find(comment);
      if (c != std::string_view::npos) text = text.substr(0, c);
    }
    text = Trim(text);
    if (!text.empty()) {
      *line = text;
      return true;
    }
  }
  return false;
}

std::string_view TextReader::RequireContentLine(std::string_view what, char comment) {
  std::string_view text;
  if (!NextContentLine(&text, comment)) {
    last_line_ = current_line_;
    Fail(fmt::format("expected {}, got end of file", what));
  }
  return text;
}

void TextReader::SkipBlanks() {
  while (pos_ < data_.size() && IsBlank(data_[pos_])) {
    if (data_[pos_] == '\n') ++current_line_;
    ++pos_;
  }
}

std::string_view TextReader::NextToken() {
  SkipBlanks();
  last_line_ = current_line_;
  std::size_t start = pos_;
  while (pos_ < data_.size() && !IsBlank(data_[pos_])) ++pos_;
  return std::string_view(data_.data() + start, pos_ - start);
}

std::string_view TextReader::PeekToken() const {
  std::size_t start = pos_;
  while (start < data_.size() && IsBlank(data_[start])) ++start;
  std::size_t end = start;
  while (end < data_.size() && !IsBlank(data_[end])) ++end;
  return std::string_view(data_.data() + start, end - start);
}

std::string_view TextReader::RequireToken(std::string_view what) {
  std::string_view token = NextToken();
  if (token.empty()) Fail(fmt::format("expected {}, got end of file", what));
  return token;
}

void TextReader::SkipRestOfLine() {
  std::string_view ignored;
  int keep = last_line_;
  NextLine(&ignored);
  last_line_ = keep;
}

std::string_view TextReader::ReadBytes(std::size_t n, std::string_view what) {
  if (n > remaining()) {
    FailAtOffset(
        fmt::format("expected {} ({} bytes), but only {} bytes remain", what, n, remaining()));
  }
  std::string_view bytes(data_.data() + pos_, n);
  Advance(n);
  last_line_ = current_line_;
  return bytes;
}

void TextReader::Seek(std::size_t offset) {
  offset = std::min(offset, data_.size());
  pos_ = 0;
  current_line_ = 1;
  Advance(offset);
  last_line_ = current_line_;
}

void TextReader::CheckCount(std::int64_t count, std::size_t min_bytes_each,
                            std::string_view what) const {
  if (count < 0) Fail(fmt::format("expected a non-negative number of {}, got {}", what, count));
  std::size_t each = std::max<std::size_t>(min_bytes_each, 1);
  if (static_cast<std::uint64_t>(count) > remaining() / each) {
    Fail(
        fmt::format("declares {} {}, but only {} bytes remain in the file (truncated file or "
                    "wrong count?)",
                    count, what, remaining()));
  }
}

std::int64_t TextReader::ToInt(std::string_view token, std::string_view what) const {
  std::int64_t value = 0;
  if (!TryParseInt(token, &value)) Fail(fmt::format("expected {}, got {}", what, Quote(token)));
  return value;
}

double TextReader::ToFinite(std::string_view token, std::string_view what) const {
  double value = 0;
  if (!TryParseDouble(token, &value) || !std::isfinite(value))
    Fail(fmt::format("expected {} (a finite number), got {}", what, Quote(token)));
  return value;
}

void TextReader::Fail(std::string_view what) const {
  ThrowInputError(source_, fmt::format("line {}", last_line_), what);
}

void TextReader::FailAtOffset(std::string_view what, std::size_t offset) const {
  ThrowInputError(source_, fmt::format("byte offset {}", offset), what);
}

}  // namespace gipsi::internal
