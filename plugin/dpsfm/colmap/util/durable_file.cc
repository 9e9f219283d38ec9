#include "dpsfm/colmap/util/durable_file.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <stdexcept>
#include <vector>

#include "dpsfm/colmap/util/input_error.h"

namespace dpsfm {

const char kAtomicWriteSuffix[] = ".tmp";

namespace {

namespace fs = std::filesystem;

std::string Reason() { return std::strerror(errno); }

// Opens `path` for writing (created or truncated) with exactly `mode`; -1
// (errno set) if it cannot be created.
int CreateForWriting(const std::string& path, unsigned int mode) {
  const int fd = ::open(path.c_str(),
                        O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC,
                        static_cast<mode_t>(mode & 07777));
  // open() honours the umask; the copy must keep the original's bits.
  if (fd >= 0) ::fchmod(fd, static_cast<mode_t>(mode & 07777));
  return fd;
}

// Writes all `size` bytes; "" or the error.
std::string WriteAll(int fd,
                     const char* data,
                     size_t size,
                     const std::string& path) {
  size_t written = 0;
  while (written < size) {
    const ssize_t n = ::write(fd, data + written, size - written);
    if (n < 0) {
      if (errno == EINTR) continue;
      return "cannot write " + path + ": " + Reason();
    }
    written += static_cast<size_t>(n);
  }
  return "";
}

// fsync and close of a file opened for writing; "" or the first error.
std::string SyncAndClose(int fd, const std::string& path, std::string error) {
  if (error.empty() && ::fsync(fd) != 0) {
    error = "cannot sync " + path + ": " + Reason();
  }
  if (::close(fd) != 0 && error.empty()) {
    error = "cannot close " + path + ": " + Reason();
  }
  return error;
}

}  // namespace

std::string ReadFileBytes(const std::string& path) {
  std::ifstream file(path, std::ios::binary);
  if (!file) throw InputError("cannot open " + path + " for reading");
  std::string bytes;
  file.seekg(0, std::ios::end);
  const std::streamoff size = file.tellg();
  if (size < 0) throw InputError("cannot read " + path);
  bytes.resize(static_cast<size_t>(size));
  file.seekg(0, std::ios::beg);
  if (size > 0 && !file.read(&bytes[0], size)) {
    throw InputError("cannot read " + path);
  }
  return bytes;
}

void WriteFileDurably(const std::string& path,
                      const std::string& contents,
                      unsigned int mode) {
  const int fd = CreateForWriting(path, mode);
  if (fd < 0)
    throw std::runtime_error("cannot create " + path + ": " + Reason());
  const std::string error = SyncAndClose(
      fd, path, WriteAll(fd, contents.data(), contents.size(), path));
  if (!error.empty()) throw std::runtime_error(error);
}

void WriteFileAtomically(const fs::path& path, const std::string& contents) {
  const fs::path tmp = path.string() + kAtomicWriteSuffix;
  WriteFileDurably(tmp.string(), contents);
  RenameOrThrow(tmp, path);
  SyncToDisk(path.parent_path().string());
}

void CopyFileDurably(const fs::path& from, const fs::path& to) {
  const int in = ::open(from.c_str(), O_RDONLY | O_CLOEXEC);
  if (in < 0) {
    throw InputError("cannot open " + from.string() + " for reading");
  }
  const int out = CreateForWriting(to.string(), FileMode(from.string()));
  if (out < 0) {
    const std::string reason = Reason();
    ::close(in);
    throw std::runtime_error("cannot create " + to.string() + ": " + reason);
  }
  std::vector<char> buffer(1 << 20);
  std::string error;
  while (error.empty()) {
    const ssize_t n = ::read(in, buffer.data(), buffer.size());
    if (n == 0) break;
    if (n < 0) {
      if (errno == EINTR) continue;
      error = "cannot read " + from.string() + ": " + Reason();
      break;
    }
    error = WriteAll(out, buffer.data(), static_cast<size_t>(n), to.string());
  }
  ::close(in);
  error = SyncAndClose(out, to.string(), error);
  if (!error.empty()) throw std::runtime_error(error);
}

void SyncToDisk(const std::string& path) {
  const std::string target = path.empty() ? "." : path;
  const int fd = ::open(target.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) {
    throw std::runtime_error("cannot open " + target + ": " + Reason());
  }
  struct stat info;
  const bool is_dir = ::fstat(fd, &info) == 0 && S_ISDIR(info.st_mode);
  const int result = ::fsync(fd);
  const int error = errno;
  ::close(fd);
  // Some file systems refuse fsync on folders; that is not a failure of
  // ours and there is nothing better to do.
  if (result != 0 && !(is_dir && (error == EINVAL || error == EROFS))) {
    throw std::runtime_error("cannot sync " + target + ": " +
                             std::strerror(error));
  }
}

void RenameOrThrow(const fs::path& from, const fs::path& to) {
  if (::rename(from.c_str(), to.c_str()) != 0) {
    throw std::runtime_error("cannot rename " + from.string() + " to " +
                             to.string() + ": " + Reason());
  }
}

void RemoveOrThrow(const fs::path& path) {
  if (::unlink(path.c_str()) != 0 && errno != ENOENT) {
    throw std::runtime_error("cannot remove " + path.string() + ": " +
                             Reason());
  }
}

unsigned int FileMode(const std::string& path) {
  struct stat info;
  if (::stat(path.c_str(), &info) != 0) return 0644;
  return static_cast<unsigned int>(info.st_mode & 07777);
}

}  // namespace dpsfm
