#include "gipsi/base/file_io.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include <fmt/format.h>

#include "gipsi/base/error.h"

namespace gipsi {
namespace {

/// Closes a file descriptor when it goes out of scope (unless released).
class FileDescriptor {
 public:
  explicit FileDescriptor(int fd) : fd_(fd) {}
  FileDescriptor(const FileDescriptor&) = delete;
  FileDescriptor& operator=(const FileDescriptor&) = delete;
  ~FileDescriptor() {
    if (fd_ >= 0) ::close(fd_);
  }
  [[nodiscard]] int get() const { return fd_; }
  /// Closes now; the errno of a failed close, else 0.
  int Close() {
    const int fd = fd_;
    fd_ = -1;
    return ::close(fd) == 0 ? 0 : errno;
  }

 private:
  int fd_;
};

[[noreturn]] void Fail(const std::filesystem::path& path, const std::filesystem::path& tmp,
                       std::string_view step, int error) {
  ::unlink(tmp.c_str());
  throw OutputError(fmt::format("{}: {}: {}", path.string(), step, std::strerror(error)));
}

}  // namespace

void WriteFileAtomically(const std::filesystem::path& path, std::string_view bytes) {
  std::filesystem::path tmp = path;
  tmp += ".tmp";
  FileDescriptor fd(::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644));
  if (fd.get() < 0) {
    const int error = errno;
    throw OutputError(
        fmt::format("{}: cannot create the file: {}", path.string(), std::strerror(error)));
  }
  while (!bytes.empty()) {
    const ssize_t n = ::write(fd.get(), bytes.data(), bytes.size());
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) Fail(path, tmp, "cannot write", errno);
    if (n == 0) Fail(path, tmp, "cannot write", EIO);
    bytes.remove_prefix(static_cast<std::size_t>(n));
  }
  if (const int error = fd.Close()) Fail(path, tmp, "cannot write", error);
  if (::rename(tmp.c_str(), path.c_str()) != 0) Fail(path, tmp, "cannot replace the file", errno);
}

std::string ReadRegularFile(const std::filesystem::path& path, std::uintmax_t max_bytes,
                            std::string_view kind) {
  auto fail = [&](const std::string& what) {
    throw InputError(fmt::format("{}: {}", path.string(), what));
  };
  // O_NONBLOCK: opening a FIFO must not wait for a writer; regular files ignore it.
  FileDescriptor fd(::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK));
  if (fd.get() < 0) fail(fmt::format("cannot open {} for reading: {}", kind, std::strerror(errno)));
  struct stat info {};
  if (::fstat(fd.get(), &info) != 0)
    fail(fmt::format("cannot open {} for reading: {}", kind, std::strerror(errno)));
  if (S_ISDIR(info.st_mode)) fail(fmt::format("is a directory, expected a {}", kind));
  if (!S_ISREG(info.st_mode))
    fail(fmt::format("is not a regular file (a device, pipe or socket), expected a {}", kind));
  const auto size = static_cast<std::uintmax_t>(info.st_size);
  if (size > max_bytes)
    fail(fmt::format("is {} bytes, over the limit of {} bytes for a {}", size, max_bytes, kind));
  std::string data(static_cast<std::size_t>(size), '\0');
  std::size_t done = 0;
  while (done < data.size()) {
    const ssize_t n = ::read(fd.get(), data.data() + done, data.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) fail(fmt::format("cannot read {}: {}", kind, std::strerror(errno)));
    if (n == 0) break;  // shrank while being read
    done += static_cast<std::size_t>(n);
  }
  data.resize(done);
  return data;
}

std::string DescribeFilesystemError(const std::filesystem::filesystem_error& e) {
  // libstdc++: "filesystem error: cannot create directories: Permission denied [out/x]".
  std::string what = e.what();
  constexpr std::string_view kPrefix = "filesystem error: ";
  if (what.starts_with(kPrefix)) what.erase(0, kPrefix.size());
  if (const auto bracket = what.find(" ["); bracket != std::string::npos) what.erase(bracket);
  if (e.path1().empty()) return what;
  return fmt::format("{}: {}", e.path1().string(), what);
}

}  // namespace gipsi
