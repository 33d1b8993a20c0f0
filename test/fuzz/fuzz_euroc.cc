// Fuzz target: EurocReader (drivers/dataset/euroc_reader.h) on a mav0 folder whose text
// files are the input's parts (split at "\n@@@@\n", fuzz_files.h): cam0/sensor.yaml,
// cam1/sensor.yaml, cam0/data.csv, cam1/data.csv, state_groundtruth_estimate0/data.csv. The
// images 1.png and 2.png of both cameras exist (tiny, fuzz_images.h); the first two frames of
// a folder that opens are read (and rectified).

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "drivers/dataset/euroc_reader.h"
#include "test/fuzz/support/fuzz_files.h"
#include "test/fuzz/support/fuzz_images.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace cblox::fuzz;
  const std::vector<std::string> parts = splitParts(data, size, 5);
  const std::string& dir = freshScratchDir();
  const char* files[] = {"mav0/cam0/sensor.yaml", "mav0/cam1/sensor.yaml", "mav0/cam0/data.csv",
                         "mav0/cam1/data.csv", "mav0/state_groundtruth_estimate0/data.csv"};
  for (size_t i = 0; i < parts.size(); ++i) {
    if (i < 4 || !parts[i].empty()) writeScratchFile(dir, files[i], parts[i]);
  }
  for (const char* image : {"mav0/cam0/data/1.png", "mav0/cam0/data/2.png", "mav0/cam1/data/1.png",
                            "mav0/cam1/data/2.png"}) {
    writeTinyImage(dir, image, TinyImage::kGray8);
  }
  std::string error;
  const std::optional<cblox::EurocReader> reader =
      cblox::EurocReader::open(dir, cblox::EurocReader::Options{}, &error);
  if (!reader) return 0;
  for (size_t i = 0; i < reader->size() && i < 2; ++i) {
    cblox::EurocStereoFrame frame;
    (void)reader->read(i, &frame, &error);
  }
  return 0;
}
