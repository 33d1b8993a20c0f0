#pragma once

// Read access to the planes of a libcamera FrameBuffer: each distinct dmabuf mapped once.

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include <libcamera/framebuffer.h>

namespace cblox {

/// The planes of one FrameBuffer mapped read-only (mmap of each plane's dmabuf fd; planes on
/// the same fd, e.g. NV12's Y and UV, share one mapping, laid out by their offsets). Owns
/// the mappings: munmap on destruction. Move-only.
/// Thread-safety: immutable after map(); plane() may be called from any thread while the
/// buffer is not being written by the camera (i.e. between a request's completion and its
/// next queueing).
class MappedFrameBuffer {
 public:
  /// Maps every plane of `buffer`. Returns std::nullopt and a message in *error (if
  /// non-null) naming the plane when a plane has no valid fd or offset, lies beyond the end
  /// of its dmabuf (when the dmabuf's size can be read with lseek), or mmap fails (errno's
  /// text). Thread-safe.
  static std::optional<MappedFrameBuffer> map(const libcamera::FrameBuffer& buffer,
                                              std::string* error);

  MappedFrameBuffer(MappedFrameBuffer&& other) noexcept;
  MappedFrameBuffer& operator=(MappedFrameBuffer&& other) noexcept;
  MappedFrameBuffer(const MappedFrameBuffer&) = delete;
  MappedFrameBuffer& operator=(const MappedFrameBuffer&) = delete;
  ~MappedFrameBuffer();

  /// Number of planes (as the FrameBuffer's). Thread-safe.
  size_t planeCount() const { return planes_.size(); }

  /// The bytes of plane i (its full length, FrameBuffer::Plane::length); i < planeCount().
  std::span<const uint8_t> plane(size_t i) const { return planes_.at(i); }

 private:
  struct Mapping {
    void* address = nullptr;
    size_t length = 0;
  };

  MappedFrameBuffer() = default;
  void unmapAll();

  std::vector<Mapping> mappings_;
  std::vector<std::span<const uint8_t>> planes_;
};

}  // namespace cblox
