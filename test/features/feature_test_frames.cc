#include "test/features/feature_test_frames.h"

#include <filesystem>
#include <map>

#include <gtest/gtest.h>

#include "drivers/open_frame_source.h"

namespace cblox::test {
namespace {

std::vector<StereoFrame> readFrames(const std::string& spec, const SourceConfig& options,
                                    size_t count) {
  std::vector<StereoFrame> frames;
  std::string error;
  std::unique_ptr<FrameSource> source = openFrameSource(spec, options, &error);
  if (source == nullptr) {
    ADD_FAILURE() << spec << ": " << error;
    return frames;
  }
  const SourceInfo& info = source->info();
  if (!info.stereo.has_value()) {
    ADD_FAILURE() << spec << " has no stereo calibration";
    return frames;
  }
  CaptureFrame frame;
  while (frames.size() < count) {
    const FrameSource::Status status = source->next(&frame, &error);
    if (status == FrameSource::Status::kEnd) break;
    if (status == FrameSource::Status::kError) {
      ADD_FAILURE() << spec << ": " << error;
      break;
    }
    StereoFrame f;
    f.name = spec + "#" + std::to_string(frame.frame_id);
    f.left = std::move(frame.left);
    f.right = std::move(frame.right);
    f.depth = std::move(frame.depth);
    f.fx = info.stereo->intrinsics.fx;
    f.baseline_m = info.stereo->baseline_m;
    frames.push_back(std::move(f));
  }
  return frames;
}

}  // namespace

const std::vector<StereoFrame>& simFrames(const std::string& scene, size_t count) {
  static std::map<std::pair<std::string, size_t>, std::vector<StereoFrame>> cache;
  const auto key = std::make_pair(scene, count);
  auto it = cache.find(key);
  if (it == cache.end()) {
    SourceConfig options;
    options.sim.rate_hz = 0.5;  // frames 2 s apart: different views
    options.max_frames = count;
    it = cache.emplace(key, readFrames("sim:" + scene, options, count)).first;
  }
  return it->second;
}

std::string eurocDir() { return std::string(CBLOX_SHARED_DATA_DIR) + "/euroc-v101-micro"; }

const std::vector<StereoFrame>& eurocFrames() {
  static const std::vector<StereoFrame> frames = [] {
    if (!std::filesystem::exists(eurocDir() + "/mav0/cam0")) return std::vector<StereoFrame>{};
    std::vector<StereoFrame> all = readFrames("euroc:" + eurocDir(), SourceConfig{}, 40);
    // The rig stands still in this window: every 10th pair is enough.
    std::vector<StereoFrame> some;
    for (size_t i = 0; i < all.size(); i += 10) some.push_back(std::move(all[i]));
    return some;
  }();
  return frames;
}

cv::Mat matView(const GrayImage& image) {
  return cv::Mat(image.height, image.width, CV_8UC1, const_cast<uint8_t*>(image.data.data()));
}

}  // namespace cblox::test
