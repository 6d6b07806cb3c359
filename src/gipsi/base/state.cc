#include "gipsi/base/state.h"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <stdexcept>

#include <fmt/format.h>

#include "gipsi/base/error.h"

namespace gipsi {

std::uint64_t NewStateStamp() {
  static std::atomic<std::uint64_t> last{0};
  return last.fetch_add(1, std::memory_order_relaxed) + 1;
}
namespace {

// Entry type codes.
constexpr char kSection = 'S', kDouble = 'd', kInt = 'i', kString = 's', kArray = 'a',
               kMatrix = 'm';

constexpr std::string_view kMagic = "GIPSI-CHECKPOINT-1\n";

std::string_view CodeName(char code) {
  switch (code) {
    case kSection:
      return "a section";
    case kDouble:
      return "a number";
    case kInt:
      return "an integer";
    case kString:
      return "a string";
    case kArray:
      return "an array";
    case kMatrix:
      return "a matrix";
    default:
      return "an unknown entry";
  }
}

/// FNV-1a, 64 bit.
std::uint64_t Hash(std::string_view bytes) {
  std::uint64_t h = 14695981039346656037ull;
  for (unsigned char c : bytes) {
    h ^= c;
    h *= 1099511628211ull;
  }
  return h;
}

void AppendU64(std::string& out, std::uint64_t x) {
  out.append(reinterpret_cast<const char*>(&x), sizeof(x));
}

std::uint64_t LoadU64(const char* p) {
  std::uint64_t x;
  std::memcpy(&x, p, sizeof(x));
  return x;
}

[[noreturn]] void ThrowIo(const std::filesystem::path& path, std::string_view what) {
  throw std::runtime_error(
      fmt::format("{}: {} failed: {}", path.string(), what, std::strerror(errno)));
}

}  // namespace

// --- StateWriter ---

void StateWriter::Raw(const void* data, std::size_t size) {
  bytes_.append(static_cast<const char*>(data), size);
}

void StateWriter::BeginSection(std::string_view tag, std::uint32_t version) {
  bytes_.push_back(kSection);
  AppendU64(bytes_, tag.size());
  bytes_.append(tag);
  AppendU64(bytes_, version);
  open_.push_back(bytes_.size());
  AppendU64(bytes_, 0);  // length, patched by EndSection
}

void StateWriter::EndSection() {
  GIPSI_CHECK(!open_.empty(), "StateWriter::EndSection without BeginSection");
  const std::size_t at = open_.back();
  open_.pop_back();
  const std::uint64_t length = bytes_.size() - at - sizeof(std::uint64_t);
  std::memcpy(bytes_.data() + at, &length, sizeof(length));
}

void StateWriter::WriteDouble(double x) {
  bytes_.push_back(kDouble);
  Raw(&x, sizeof(x));
}

void StateWriter::WriteInt(std::int64_t x) {
  bytes_.push_back(kInt);
  Raw(&x, sizeof(x));
}

void StateWriter::WriteString(std::string_view s) {
  bytes_.push_back(kString);
  AppendU64(bytes_, s.size());
  bytes_.append(s);
}

void StateWriter::WriteArrayBytes(std::size_t element_size, std::size_t count, const void* data) {
  bytes_.push_back(kArray);
  AppendU64(bytes_, element_size);
  AppendU64(bytes_, count);
  if (count > 0) Raw(data, element_size * count);
}

void StateWriter::WriteMatrixBytes(std::size_t element_size, Index rows, Index cols,
                                   const void* data) {
  bytes_.push_back(kMatrix);
  AppendU64(bytes_, element_size);
  AppendU64(bytes_, static_cast<std::uint64_t>(rows));
  AppendU64(bytes_, static_cast<std::uint64_t>(cols));
  if (rows * cols > 0) Raw(data, element_size * static_cast<std::size_t>(rows * cols));
}

// --- StateReader ---

StateReader::StateReader(std::string bytes, std::string source)
    : bytes_(std::move(bytes)), source_(std::move(source)) {}

void StateReader::Fail(std::string_view what) const {
  std::string path;
  for (const Open& o : open_) path += (path.empty() ? "" : "/") + o.tag;
  throw InputError(fmt::format("{}: {}{}", source_, path.empty() ? "" : path + ": ", what));
}

void StateReader::ReadBytes(void* out, std::size_t size) {
  const std::size_t limit = open_.empty() ? bytes_.size() : open_.back().end;
  if (size > limit - pos_) Fail("the data ends early (truncated or from another scene)");
  if (size > 0) std::memcpy(out, bytes_.data() + pos_, size);
  pos_ += size;
}

std::uint64_t StateReader::ReadU64() {
  std::uint64_t x;
  ReadBytes(&x, sizeof(x));
  return x;
}

void StateReader::Expect(char code, std::string_view what) {
  char got = 0;
  ReadBytes(&got, 1);
  ++(open_.empty() ? top_entries_ : open_.back().entries);
  if (got != code)
    Fail(
        fmt::format("expected {} ({}) but found {}; the checkpoint is from another scene or "
                    "version",
                    CodeName(code), what, CodeName(got)));
}

void StateReader::BeginSection(std::string_view tag, std::uint32_t version) {
  Expect(kSection, fmt::format("section '{}'", tag));
  const std::uint64_t size = ReadU64();
  if (size > bytes_.size()) Fail("corrupted section tag");
  std::string got(size, '\0');
  ReadBytes(got.data(), size);
  if (got != tag)
    Fail(
        fmt::format("expected state of '{}' but the checkpoint has '{}' here; it was written "
                    "for another scene",
                    tag, got));
  const std::uint64_t got_version = ReadU64();
  if (got_version != version)
    Fail(fmt::format("'{}' state has format version {}, this build reads version {}", tag,
                     got_version, version));
  const std::uint64_t length = ReadU64();
  const std::size_t limit = open_.empty() ? bytes_.size() : open_.back().end;
  if (length > limit - pos_) Fail(fmt::format("section '{}' is truncated", tag));
  open_.push_back({std::string(tag), pos_ + static_cast<std::size_t>(length), version, 0});
}

void StateReader::EndSection() {
  GIPSI_CHECK(!open_.empty(), "StateReader::EndSection without BeginSection");
  if (pos_ != open_.back().end)
    Fail(
        fmt::format("{} unread bytes at the end of the section; the checkpoint was written for "
                    "another scene or version",
                    open_.back().end - pos_));
  open_.pop_back();
}

void StateReader::SkipBytes(std::uint64_t size) {
  const std::size_t limit = open_.empty() ? bytes_.size() : open_.back().end;
  if (size > limit - pos_) Fail("the data ends early (truncated or from another scene)");
  pos_ += static_cast<std::size_t>(size);
}

void StateReader::SkipRestOfSection() {
  GIPSI_CHECK(!open_.empty(), "StateReader::SkipRestOfSection outside a section");
  pos_ = open_.back().end;
}

bool StateReader::NextIsSection(std::string_view tag) const {
  const std::size_t limit = open_.empty() ? bytes_.size() : open_.back().end;
  std::size_t at = pos_;
  if (at >= limit || bytes_[at] != kSection) return false;
  ++at;
  std::uint64_t size = 0;
  if (limit - at < sizeof(size)) return false;
  std::memcpy(&size, bytes_.data() + at, sizeof(size));
  at += sizeof(size);
  return size == tag.size() && limit - at >= size && bytes_.compare(at, size, tag) == 0;
}

void StateReader::SkipEntry() {
  char code = 0;
  ReadBytes(&code, 1);
  ++(open_.empty() ? top_entries_ : open_.back().entries);
  // A count of values times their size, refused before it could overflow.
  auto product = [&](std::uint64_t a, std::uint64_t b) {
    if (a != 0 && b > (bytes_.size() - pos_) / a) Fail("an entry runs past the end of the data");
    return a * b;
  };
  switch (code) {
    case kSection: {
      SkipBytes(ReadU64());  // the tag
      (void)ReadU64();       // the version
      SkipBytes(ReadU64());
      return;
    }
    case kDouble:
    case kInt:
      return SkipBytes(8);
    case kString:
      return SkipBytes(ReadU64());
    case kArray: {
      const std::uint64_t size = ReadU64();
      return SkipBytes(product(size, ReadU64()));
    }
    case kMatrix: {
      const std::uint64_t size = ReadU64();
      const std::uint64_t rows = ReadU64();
      return SkipBytes(product(size, product(rows, ReadU64())));
    }
    default:
      Fail(
          fmt::format("an unknown entry (code {}); the data is corrupted", static_cast<int>(code)));
  }
}

StateReader::Position StateReader::position() const {
  Position at;
  for (std::size_t i = 0; i < open_.size(); ++i) {
    // A section counts as read in its parent once entered.
    at.index.push_back((i == 0 ? top_entries_ : open_[i - 1].entries) - 1);
    at.tags.push_back(open_[i].tag);
    at.versions.push_back(open_[i].version);
  }
  at.index.push_back(open_.empty() ? top_entries_ : open_.back().entries);
  return at;
}

void StateReader::Seek(const Position& at) {
  GIPSI_CHECK(pos_ == 0 && open_.empty() && top_entries_ == 0, "StateReader::Seek after reading");
  GIPSI_CHECK(at.index.size() == at.tags.size() + 1 && at.tags.size() == at.versions.size(),
              "StateReader::Seek: a malformed position");
  for (std::size_t i = 0; i < at.index.size(); ++i) {
    for (std::uint64_t k = 0; k < at.index[i]; ++k) SkipEntry();
    if (i < at.tags.size()) BeginSection(at.tags[i], at.versions[i]);
  }
}

double StateReader::ReadDouble() {
  Expect(kDouble, "number");
  double x;
  ReadBytes(&x, sizeof(x));
  return x;
}

std::int64_t StateReader::ReadInt() {
  Expect(kInt, "integer");
  std::int64_t x;
  ReadBytes(&x, sizeof(x));
  return x;
}

std::string StateReader::ReadString() {
  Expect(kString, "string");
  const std::uint64_t size = ReadU64();
  if (size > bytes_.size() - pos_) Fail("a string runs past the end of the data");
  std::string s(size, '\0');
  ReadBytes(s.data(), size);
  return s;
}

std::size_t StateReader::ReadArrayHeader(std::size_t element_size) {
  Expect(kArray, "array");
  const std::uint64_t size = ReadU64();
  const std::uint64_t count = ReadU64();
  if (size != element_size)
    Fail(fmt::format("array of {}-byte values where {}-byte values were expected", size,
                     element_size));
  if (count > (bytes_.size() - pos_) / std::max<std::size_t>(1, element_size))
    Fail("an array runs past the end of the data");
  return static_cast<std::size_t>(count);
}

std::pair<Index, Index> StateReader::ReadMatrixHeader(std::size_t element_size) {
  Expect(kMatrix, "matrix");
  const std::uint64_t size = ReadU64();
  const std::uint64_t rows = ReadU64();
  const std::uint64_t cols = ReadU64();
  if (size != element_size)
    Fail(fmt::format("matrix of {}-byte values where {}-byte values were expected", size,
                     element_size));
  const std::uint64_t available = (bytes_.size() - pos_) / element_size;
  // An empty matrix (3 by 0) holds no values: its shape alone must not be checked against
  // what is left (it may be the last entry).
  if (rows > 0 && cols > 0 && (rows > available || cols > available / rows))
    Fail("a matrix runs past the end of the data");
  return {static_cast<Index>(rows), static_cast<Index>(cols)};
}

void StateReader::ShapeError(std::string_view what, std::size_t rows, std::size_t cols,
                             std::size_t got_rows, std::size_t got_cols) const {
  Fail(
      fmt::format("{} is {} by {} in the checkpoint but {} by {} in this scene; the checkpoint "
                  "was written for another scene",
                  what, got_rows, got_cols, rows, cols));
}

// --- Files ---

void WriteCheckpointFile(const std::filesystem::path& path, std::string_view payload) {
  std::string data(kMagic);
  AppendU64(data, payload.size());
  AppendU64(data, Hash(payload));
  data.append(payload);

  std::filesystem::path tmp = path;
  tmp += ".tmp";
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) ThrowIo(tmp, "creating the checkpoint");
  std::size_t done = 0;
  while (done < data.size()) {
    const ssize_t n = ::write(fd, data.data() + done, data.size() - done);
    if (n < 0) {
      if (errno == EINTR) continue;
      ::close(fd);
      ThrowIo(tmp, "writing the checkpoint");
    }
    done += static_cast<std::size_t>(n);
  }
  if (::fsync(fd) != 0) {
    ::close(fd);
    ThrowIo(tmp, "fsync");
  }
  if (::close(fd) != 0) ThrowIo(tmp, "closing the checkpoint");
  if (std::rename(tmp.c_str(), path.c_str()) != 0) ThrowIo(path, "renaming the checkpoint");
  const std::filesystem::path dir = path.has_parent_path() ? path.parent_path() : ".";
  const int dfd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (dfd >= 0) {  // best effort: the rename is already atomic
    ::fsync(dfd);
    ::close(dfd);
  }
}

std::string ReadCheckpointFile(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) ThrowInputError(path.string(), "", "cannot open the checkpoint");
  std::string data((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::size_t header = kMagic.size() + 2 * sizeof(std::uint64_t);
  if (data.size() < kMagic.size() || data.compare(0, kMagic.size(), kMagic) != 0)
    ThrowInputError(path.string(), "", "not a GiPSi checkpoint (bad magic string)");
  if (data.size() < header)
    ThrowInputError(path.string(), "", "the checkpoint is truncated (incomplete header)");
  const std::uint64_t size = LoadU64(data.data() + kMagic.size());
  const std::uint64_t hash = LoadU64(data.data() + kMagic.size() + sizeof(std::uint64_t));
  if (data.size() - header != size)
    ThrowInputError(path.string(), "",
                    fmt::format("the checkpoint is truncated or has trailing data ({} bytes of "
                                "state, the header says {})",
                                data.size() - header, size));
  std::string payload = data.substr(header);
  if (Hash(payload) != hash)
    ThrowInputError(path.string(), "", "the checkpoint is corrupted (checksum mismatch)");
  return payload;
}

}  // namespace gipsi
