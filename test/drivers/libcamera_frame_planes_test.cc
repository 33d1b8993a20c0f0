#include "drivers/libcamera/frame_planes.h"

#include <sys/mman.h>
#include <unistd.h>

#include <cstdint>
#include <memory>
#include <numeric>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <libcamera/base/shared_fd.h>
#include <libcamera/base/unique_fd.h>
#include <libcamera/framebuffer.h>

#include "drivers/libcamera/mapped_frame_buffer.h"
#include "drivers/pixel/pixel_convert.h"
#include "test/test_support/contains.h"

namespace cblox {
namespace {

using test::contains;

std::vector<uint8_t> ramp(size_t n, uint8_t start = 0) {
  std::vector<uint8_t> bytes(n);
  std::iota(bytes.begin(), bytes.end(), start);
  return bytes;
}

TEST(LibcameraFramePlanes, SinglePlaneIsUsedInPlace) {
  const std::vector<uint8_t> yuyv = ramp(4 * 2 * 2);
  std::vector<uint8_t> scratch;
  const FramePlane plane{yuyv, 0};
  const RawImage raw = assembleRawImage(PixelFormat::kYuyv, 4, 2, 8, {&plane, 1}, &scratch);
  EXPECT_EQ(raw.format, PixelFormat::kYuyv);
  EXPECT_EQ(raw.width, 4);
  EXPECT_EQ(raw.height, 2);
  EXPECT_EQ(raw.stride, 8u);
  EXPECT_EQ(raw.data, yuyv.data());
  EXPECT_EQ(raw.bytes, yuyv.size());  // bytes_used 0: the whole plane
  EXPECT_TRUE(scratch.empty());
  GrayImage gray;
  ASSERT_TRUE(toGray(raw, &gray));
  EXPECT_EQ(gray(1, 0), 2);  // Y1 of the first pair: byte 2
}

TEST(LibcameraFramePlanes, MjpegTakesTheBytesUsed) {
  const std::vector<uint8_t> buffer = ramp(1000);
  std::vector<uint8_t> scratch;
  const FramePlane plane{buffer, 321};
  const RawImage raw = assembleRawImage(PixelFormat::kMjpeg, 64, 48, 0, {&plane, 1}, &scratch);
  EXPECT_EQ(raw.data, buffer.data());
  EXPECT_EQ(raw.bytes, 321u);
}

TEST(LibcameraFramePlanes, BackToBackPlanesOfOneBufferAreUsedInPlace) {
  // NV12 4x2, stride 6: Y plane 12 bytes, then the UV plane 6 bytes, in one buffer.
  const std::vector<uint8_t> buffer = ramp(18);
  std::vector<uint8_t> scratch;
  const std::span<const uint8_t> all(buffer);
  const FramePlane planes[] = {{all.subspan(0, 12), 12}, {all.subspan(12, 6), 6}};
  const RawImage raw = assembleRawImage(PixelFormat::kNv12, 4, 2, 6, planes, &scratch);
  EXPECT_EQ(raw.data, buffer.data());
  EXPECT_EQ(raw.bytes, 18u);
  EXPECT_TRUE(scratch.empty());
  ColorImage color;
  EXPECT_TRUE(toColor(raw, &color)) << toColor(raw, &color).message;
}

TEST(LibcameraFramePlanes, SeparatePlanesAreGathered) {
  // YUV420 4x4, stride 4: Y 16 bytes, U 4, V 4, each in its own buffer (with slack).
  const std::vector<uint8_t> y = ramp(20, 100), u = ramp(8, 10), v = ramp(8, 50);
  std::vector<uint8_t> scratch;
  const FramePlane planes[] = {{y, 16}, {u, 4}, {v, 4}};
  const RawImage raw = assembleRawImage(PixelFormat::kYuv420, 4, 4, 4, planes, &scratch);
  ASSERT_EQ(raw.data, scratch.data());
  ASSERT_EQ(raw.bytes, 24u);
  EXPECT_EQ(std::vector<uint8_t>(scratch.begin(), scratch.begin() + 16),
            std::vector<uint8_t>(y.begin(), y.begin() + 16));
  EXPECT_EQ(std::vector<uint8_t>(scratch.begin() + 16, scratch.begin() + 20),
            std::vector<uint8_t>(u.begin(), u.begin() + 4));
  EXPECT_EQ(std::vector<uint8_t>(scratch.begin() + 20, scratch.end()),
            std::vector<uint8_t>(v.begin(), v.begin() + 4));
  GrayImage gray;
  ASSERT_TRUE(toGray(raw, &gray));
  EXPECT_EQ(gray(3, 3), 115);
}

TEST(LibcameraFramePlanes, ShortPlaneIsCaughtByTheConverter) {
  const std::vector<uint8_t> y = ramp(16), uv = ramp(8);
  std::vector<uint8_t> scratch;
  const FramePlane planes[] = {{y, 10}, {uv, 8}};  // the camera wrote 10 of 16 luma bytes
  const RawImage raw = assembleRawImage(PixelFormat::kNv12, 4, 4, 4, planes, &scratch);
  GrayImage gray;
  const ConvertResult result = toGray(raw, &gray);
  EXPECT_EQ(result.error, ConvertError::kShortBuffer) << result.message;
  // No planes at all: an empty image, also refused.
  const RawImage none = assembleRawImage(PixelFormat::kGrey, 4, 4, 4, {}, &scratch);
  EXPECT_EQ(toGray(none, &gray).error, ConvertError::kShortBuffer);
}

// A memfd stands in for a dmabuf: MappedFrameBuffer only needs an fd it can mmap.
libcamera::SharedFD memfdWith(const std::vector<uint8_t>& bytes) {
  const int fd = memfd_create("cblox_libcamera_test", 0);
  EXPECT_GE(fd, 0);
  EXPECT_EQ(write(fd, bytes.data(), bytes.size()), static_cast<ssize_t>(bytes.size()));
  return libcamera::SharedFD(libcamera::UniqueFD(fd));
}

TEST(LibcameraMappedFrameBuffer, MapsPlanesSharingOneFdAtTheirOffsets) {
  const std::vector<uint8_t> bytes = ramp(100);
  const libcamera::SharedFD fd = memfdWith(bytes);
  std::vector<libcamera::FrameBuffer::Plane> planes(2);
  planes[0].fd = fd;
  planes[0].offset = 0;
  planes[0].length = 60;
  planes[1].fd = fd;
  planes[1].offset = 60;
  planes[1].length = 30;
  const libcamera::FrameBuffer buffer(planes);
  std::string error;
  std::optional<MappedFrameBuffer> mapped = MappedFrameBuffer::map(buffer, &error);
  ASSERT_TRUE(mapped.has_value()) << error;
  ASSERT_EQ(mapped->planeCount(), 2u);
  EXPECT_EQ(mapped->plane(0).size(), 60u);
  EXPECT_EQ(mapped->plane(1).size(), 30u);
  EXPECT_EQ(mapped->plane(0)[5], 5);
  EXPECT_EQ(mapped->plane(1)[0], 60);
  EXPECT_EQ(mapped->plane(1).data(), mapped->plane(0).data() + 60);  // one mapping
  // Moving keeps the mapping alive.
  MappedFrameBuffer moved = std::move(*mapped);
  EXPECT_EQ(moved.plane(1)[29], 89);
}

TEST(LibcameraMappedFrameBuffer, RefusesPlanesBeyondTheBufferOrWithoutFd) {
  const libcamera::SharedFD fd = memfdWith(ramp(64));
  std::vector<libcamera::FrameBuffer::Plane> planes(1);
  planes[0].fd = fd;
  planes[0].offset = 32;
  planes[0].length = 64;
  std::string error;
  EXPECT_FALSE(MappedFrameBuffer::map(libcamera::FrameBuffer(planes), &error).has_value());
  EXPECT_TRUE(contains(error,
                       "plane 0 (offset 32, length 64) lies beyond the end of its "
                       "dmabuf (64 bytes)"));
  planes[0].fd = libcamera::SharedFD();
  EXPECT_FALSE(MappedFrameBuffer::map(libcamera::FrameBuffer(planes), &error).has_value());
  EXPECT_TRUE(contains(error, "plane 0 has no dmabuf fd"));
  // (A plane without a valid offset cannot be built: libcamera's FrameBuffer asserts.)
}

}  // namespace
}  // namespace cblox
