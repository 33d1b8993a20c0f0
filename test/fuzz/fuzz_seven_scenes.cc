// Fuzz target: SevenScenesReader (drivers/dataset/seven_scenes_reader.h) on a folder whose
// text files are the input's parts (split at "\n@@@@\n", fuzz_files.h):
// camera-intrinsics.txt, frame-000000.pose.txt, frame-000001.pose.txt. The depth and colour
// images of both frames exist (tiny, fuzz_images.h); the frames of a folder that opens are
// read.

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "drivers/dataset/seven_scenes_reader.h"
#include "test/fuzz/support/fuzz_files.h"
#include "test/fuzz/support/fuzz_images.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace cblox::fuzz;
  const std::vector<std::string> parts = splitParts(data, size, 3);
  const std::string& dir = freshScratchDir();
  writeScratchFile(dir, "camera-intrinsics.txt", parts[0]);
  for (const int frame : {0, 1}) {
    const std::string stem = "frame-00000" + std::to_string(frame);
    writeScratchFile(dir, stem + ".pose.txt", parts[1 + frame]);
    writeTinyImage(dir, stem + ".depth.png", TinyImage::kDepth16);
    writeTinyImage(dir, stem + ".color.png", TinyImage::kColor8);
  }
  std::string error;
  const std::optional<cblox::SevenScenesReader> reader =
      cblox::SevenScenesReader::open(dir, &error);
  if (!reader) return 0;
  for (size_t i = 0; i < reader->size(); ++i) {
    cblox::SevenScenesFrame frame;
    (void)reader->read(i, &frame, &error);
  }
  return 0;
}
