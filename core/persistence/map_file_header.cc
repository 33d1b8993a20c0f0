#include "core/persistence/map_file_header.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>

#include <xxhash.h>

#include "core/persistence/byte_codec.h"

namespace cblox {
namespace {

using persistence_detail::ByteReader;
using persistence_detail::ByteWriter;

std::optional<MapFile> fail(std::string* error, const std::string& path, const std::string& what) {
  if (error != nullptr) *error = path + ": " + what;
  return std::nullopt;
}

// Reads exactly n bytes at the current offset; false with errno set (0 at a short read).
bool readExactly(int fd, char* out, size_t n) {
  while (n > 0) {
    const ssize_t got = ::read(fd, out, n);
    if (got < 0) {
      if (errno == EINTR) continue;
      return false;
    }
    if (got == 0) {
      errno = 0;
      return false;
    }
    out += got;
    n -= static_cast<size_t>(got);
  }
  return true;
}

// Closes the descriptor on every path out of readMapFile.
struct FdCloser {
  int fd;
  ~FdCloser() { ::close(fd); }
};

std::string hex(uint64_t v) {
  char buffer[24];
  std::snprintf(buffer, sizeof(buffer), "%016llx", static_cast<unsigned long long>(v));
  return buffer;
}

std::string printable(std::string_view bytes) {
  std::string out;
  for (const char c : bytes) {
    if (c >= 0x20 && c < 0x7f) {
      out.push_back(c);
    } else {
      char buffer[8];
      std::snprintf(buffer, sizeof(buffer), "\\x%02x", static_cast<unsigned char>(c));
      out += buffer;
    }
  }
  return out;
}

}  // namespace

uint64_t mapFileChecksum(std::string_view bytes) { return XXH64(bytes.data(), bytes.size(), 0); }

std::string sealMapFile(std::string_view magic, uint32_t version, std::string_view payload) {
  std::string out;
  out.reserve(kMapFileHeaderBytes + payload.size());
  ByteWriter w(&out);
  w.bytes(magic.substr(0, 8));
  w.u32(version);
  w.u32(0);
  w.u64(payload.size());
  w.u64(mapFileChecksum(payload));
  w.bytes(payload);
  return out;
}

std::optional<MapFile> readMapFile(const std::string& path, std::string_view magic,
                                   uint32_t newest_version, std::string_view what,
                                   std::string* error) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0)
    return fail(error, path, "cannot open " + std::string(what) + ": " + std::strerror(errno));
  const FdCloser closer{fd};
  struct stat st {};
  if (::fstat(fd, &st) != 0)
    return fail(error, path, std::string("fstat failed: ") + std::strerror(errno));
  if (!S_ISREG(st.st_mode)) return fail(error, path, std::string(what) + " is not a regular file");
  const auto file_size = static_cast<uint64_t>(st.st_size);
  if (file_size < kMapFileHeaderBytes) {
    return fail(error, path,
                "truncated: " + std::to_string(file_size) + " bytes, shorter than the " +
                    std::to_string(kMapFileHeaderBytes) + "-byte header of a " + std::string(what));
  }
  char header[kMapFileHeaderBytes];
  if (!readExactly(fd, header, sizeof(header))) {
    return fail(error, path,
                std::string("read failed: ") +
                    (errno == 0 ? "unexpected end of file" : std::strerror(errno)));
  }
  ByteReader r(std::string_view(header, sizeof(header)));
  std::string_view file_magic;
  uint32_t version = 0, flags = 0;
  uint64_t payload_length = 0, payload_xxh64 = 0;
  r.bytes(8, &file_magic);
  r.u32(&version);
  r.u32(&flags);
  r.u64(&payload_length);
  r.u64(&payload_xxh64);
  if (file_magic != magic) {
    return fail(error, path,
                "bad magic \"" + printable(file_magic) + "\": not a cblox " + std::string(what) +
                    " (expected \"" + std::string(magic) + "\")");
  }
  if (version == 0) return fail(error, path, "invalid format version 0");
  if (version > newest_version) {
    return fail(error, path,
                std::string(what) + " format version " + std::to_string(version) +
                    " is newer than this reader supports (" + std::to_string(newest_version) +
                    "); use a newer cblox");
  }
  if (flags != 0) return fail(error, path, "unknown header flags " + hex(flags));
  const uint64_t available = file_size - kMapFileHeaderBytes;
  if (payload_length != available) {
    return fail(error, path,
                (payload_length > available ? "truncated: payload length " : "payload length ") +
                    std::to_string(payload_length) + " out of bounds: the file holds " +
                    std::to_string(available) + " bytes after the header");
  }
  MapFile file;
  file.version = version;
  file.file_size = file_size;
  file.payload.resize(payload_length);  // == the file's actual size: bounded
  if (!readExactly(fd, file.payload.data(), file.payload.size())) {
    return fail(error, path,
                std::string("read failed: ") +
                    (errno == 0 ? "unexpected end of file" : std::strerror(errno)));
  }
  file.payload_xxh64 = mapFileChecksum(file.payload);
  if (file.payload_xxh64 != payload_xxh64) {
    return fail(error, path,
                "checksum mismatch: payload XXH64 is " + hex(file.payload_xxh64) +
                    ", the header says " + hex(payload_xxh64) + " (the file is corrupt)");
  }
  return file;
}

}  // namespace cblox
