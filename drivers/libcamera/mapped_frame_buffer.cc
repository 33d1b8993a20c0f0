#include "drivers/libcamera/mapped_frame_buffer.h"

#include <sys/mman.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <map>
#include <utility>

namespace cblox {

std::optional<MappedFrameBuffer> MappedFrameBuffer::map(const libcamera::FrameBuffer& buffer,
                                                        std::string* error) {
  const auto fail = [error](const std::string& message) {
    if (error != nullptr) *error = message;
    return std::nullopt;
  };
  const std::vector<libcamera::FrameBuffer::Plane>& planes = buffer.planes();
  if (planes.empty()) return fail("frame buffer has no planes");
  // Bytes to map per fd: up to the end of its last plane.
  std::map<int, size_t> extent;
  for (size_t i = 0; i < planes.size(); ++i) {
    const libcamera::FrameBuffer::Plane& plane = planes[i];
    const int fd = plane.fd.get();
    if (fd < 0) return fail("frame buffer plane " + std::to_string(i) + " has no dmabuf fd");
    if (plane.offset == libcamera::FrameBuffer::Plane::kInvalidOffset) {
      return fail("frame buffer plane " + std::to_string(i) + " has no valid offset");
    }
    const size_t end = size_t{plane.offset} + plane.length;
    const off_t size = lseek(fd, 0, SEEK_END);
    if (size >= 0 && end > static_cast<size_t>(size)) {
      return fail("frame buffer plane " + std::to_string(i) + " (offset " +
                  std::to_string(plane.offset) + ", length " + std::to_string(plane.length) +
                  ") lies beyond the end of its dmabuf (" + std::to_string(size) + " bytes)");
    }
    extent[fd] = std::max(extent[fd], end);
  }

  MappedFrameBuffer mapped;
  std::map<int, const uint8_t*> base;
  for (const auto& [fd, length] : extent) {
    void* address = mmap(nullptr, length, PROT_READ, MAP_SHARED, fd, 0);
    if (address == MAP_FAILED) {
      return fail("cannot mmap a frame buffer plane (fd " + std::to_string(fd) + ", " +
                  std::to_string(length) + " bytes): " + std::strerror(errno));
    }
    mapped.mappings_.push_back({address, length});
    base[fd] = static_cast<const uint8_t*>(address);
  }
  for (const libcamera::FrameBuffer::Plane& plane : planes) {
    mapped.planes_.emplace_back(base[plane.fd.get()] + plane.offset, plane.length);
  }
  return mapped;
}

MappedFrameBuffer::MappedFrameBuffer(MappedFrameBuffer&& other) noexcept
    : mappings_(std::exchange(other.mappings_, {})), planes_(std::exchange(other.planes_, {})) {}

MappedFrameBuffer& MappedFrameBuffer::operator=(MappedFrameBuffer&& other) noexcept {
  if (this != &other) {
    unmapAll();
    mappings_ = std::exchange(other.mappings_, {});
    planes_ = std::exchange(other.planes_, {});
  }
  return *this;
}

MappedFrameBuffer::~MappedFrameBuffer() { unmapAll(); }

void MappedFrameBuffer::unmapAll() {
  for (const Mapping& mapping : mappings_) munmap(mapping.address, mapping.length);
  mappings_.clear();
  planes_.clear();
}

}  // namespace cblox
