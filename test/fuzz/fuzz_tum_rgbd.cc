// Fuzz target: TumRgbdReader (drivers/dataset/tum_rgbd_reader.h) on a folder whose text files
// are the input's parts (split at "\n@@@@\n", fuzz_files.h): rgb.txt, depth.txt,
// groundtruth.txt, camera-intrinsics.txt (the last two only when not empty). The images
// rgb/1.png, rgb/2.png, depth/1.png and depth/2.png exist (tiny, fuzz_images.h); the first
// two frames of a folder that opens are read.

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "drivers/dataset/tum_rgbd_reader.h"
#include "test/fuzz/support/fuzz_files.h"
#include "test/fuzz/support/fuzz_images.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace cblox::fuzz;
  const std::vector<std::string> parts = splitParts(data, size, 4);
  const std::string& dir = freshScratchDir();
  const char* files[] = {"rgb.txt", "depth.txt", "groundtruth.txt", "camera-intrinsics.txt"};
  for (size_t i = 0; i < parts.size(); ++i) {
    if (i < 2 || !parts[i].empty()) writeScratchFile(dir, files[i], parts[i]);
  }
  writeTinyImage(dir, "rgb/1.png", TinyImage::kColor8);
  writeTinyImage(dir, "rgb/2.png", TinyImage::kColor8);
  writeTinyImage(dir, "depth/1.png", TinyImage::kDepth16);
  writeTinyImage(dir, "depth/2.png", TinyImage::kDepth16);
  std::string error;
  const std::optional<cblox::TumRgbdReader> reader =
      cblox::TumRgbdReader::open(dir, cblox::TumRgbdReader::Options{}, &error);
  if (!reader) return 0;
  for (size_t i = 0; i < reader->size() && i < 2; ++i) {
    cblox::TumRgbdFrame frame;
    (void)reader->read(i, &frame, &error);
  }
  return 0;
}
