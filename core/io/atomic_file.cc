#include "core/io/atomic_file.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstring>

namespace cblox {
namespace {

std::atomic<unsigned long long> g_temp_counter{0};

bool fail(std::string* error, const std::string& path, const char* step, int errnum) {
  if (error != nullptr) *error = path + ": " + step + " failed: " + std::strerror(errnum);
  return false;
}

// The directory holding `path` ("." when it has no slash).
std::string parentDirectory(const std::string& path) {
  const size_t slash = path.find_last_of('/');
  if (slash == std::string::npos) return ".";
  if (slash == 0) return "/";
  return path.substr(0, slash);
}

bool writeAll(int fd, std::string_view data) {
  const char* p = data.data();
  size_t left = data.size();
  while (left > 0) {
    const ssize_t n = ::write(fd, p, left);
    if (n < 0) {
      if (errno == EINTR) continue;
      return false;
    }
    p += n;
    left -= static_cast<size_t>(n);
  }
  return true;
}

}  // namespace

bool syncDirectory(const std::string& dir, std::string* error) {
  const int fd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) return fail(error, dir, "open of the directory", errno);
  if (::fsync(fd) != 0) {
    const int errnum = errno;
    ::close(fd);
    return fail(error, dir, "fsync of the directory", errnum);
  }
  ::close(fd);
  return true;
}

bool writeFileAtomically(const std::string& path, std::string_view data, std::string* error) {
  const std::string temp = path + ".tmp." + std::to_string(::getpid()) + "." +
                           std::to_string(g_temp_counter.fetch_add(1, std::memory_order_relaxed));
  const int fd = ::open(temp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) return fail(error, path, ("create of " + temp).c_str(), errno);
  const auto abandon = [&](const char* step, int errnum) {
    ::close(fd);
    ::unlink(temp.c_str());
    return fail(error, path, step, errnum);
  };
  if (!writeAll(fd, data)) return abandon("write", errno);
  if (::fsync(fd) != 0) return abandon("fsync", errno);
  if (::close(fd) != 0) {
    const int errnum = errno;
    ::unlink(temp.c_str());
    return fail(error, path, "close", errnum);
  }
  if (::rename(temp.c_str(), path.c_str()) != 0) {
    const int errnum = errno;
    ::unlink(temp.c_str());
    return fail(error, path, "rename", errnum);
  }
  std::string dir_error;
  if (!syncDirectory(parentDirectory(path), &dir_error)) {
    if (error != nullptr) *error = path + ": renamed, but " + dir_error;
    return false;
  }
  return true;
}

}  // namespace cblox
