// Fuzz target: KittiOdometryReader (drivers/dataset/kitti_odometry_reader.h) on a sequence
// folder whose text files are the input's parts (split at "\n@@@@\n", fuzz_files.h):
// calib.txt, times.txt, poses.txt (absent when its part is empty). The images 000000.png and
// 000001.png of both cameras exist (tiny grey, fuzz_images.h); every pair of a folder that
// opens is read.

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "drivers/dataset/kitti_odometry_reader.h"
#include "test/fuzz/support/fuzz_files.h"
#include "test/fuzz/support/fuzz_images.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace cblox::fuzz;
  const std::vector<std::string> parts = splitParts(data, size, 3);
  const std::string& dir = freshScratchDir();
  const char* files[] = {"calib.txt", "times.txt", "poses.txt"};
  for (size_t i = 0; i < parts.size(); ++i) {
    if (i < 2 || !parts[i].empty()) writeScratchFile(dir, files[i], parts[i]);
  }
  for (const char* image :
       {"image_0/000000.png", "image_0/000001.png", "image_1/000000.png", "image_1/000001.png"}) {
    writeTinyImage(dir, image, TinyImage::kGray8);
  }
  std::string error;
  const std::optional<cblox::KittiOdometryReader> reader =
      cblox::KittiOdometryReader::open(dir, &error);
  if (!reader) return 0;
  for (size_t i = 0; i < reader->size(); ++i) {
    cblox::KittiStereoFrame frame;
    (void)reader->read(i, &frame, &error);
  }
  return 0;
}
