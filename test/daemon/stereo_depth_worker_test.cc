#include "daemon/capture/stereo_depth_worker.h"

#include <atomic>
#include <mutex>
#include <vector>

#include <gtest/gtest.h>

namespace cblox {
namespace {

std::unique_ptr<StereoDepthEstimator> estimator() {
  RectifiedStereoCalibration calibration;
  calibration.intrinsics = {100.0, 100.0, 79.5, 59.5, 160, 120};
  calibration.baseline_m = 0.1;
  StereoDepthConfig config;
  config.downscale = 1;
  config.num_disparities = 16;
  return StereoDepthEstimator::create(calibration, config, nullptr);
}

CaptureFrame pair(int64_t id, int64_t t_ns, int width = 160) {
  CaptureFrame frame;
  frame.frame_id = id;
  frame.timestamp_ns = t_ns;
  frame.left = GrayImage(width, 120, 100);
  frame.right = GrayImage(width, 120, 100);
  return frame;
}

TEST(StereoDepthWorkerTest, PublishesEveryPairItKeepsUpWithAndTheLast) {
  std::mutex mutex;
  std::vector<int64_t> published;
  {
    StereoDepthWorker worker(estimator(), 0.0, [&](const CaptureFrame& frame) {
      EXPECT_EQ(frame.depth.width, 160);
      EXPECT_TRUE(frame.left.empty());
      std::lock_guard<std::mutex> lock(mutex);
      published.push_back(frame.frame_id);
    });
    for (int64_t i = 0; i < 20; ++i) worker.offer(pair(i, i * 50'000'000));
    worker.drain();
    const StereoDepthWorkerStats stats = worker.stats();
    EXPECT_EQ(stats.computed + stats.superseded, 20u);  // newest wins, nothing else lost
    EXPECT_EQ(stats.computed, published.size());
    ASSERT_FALSE(published.empty());
    EXPECT_EQ(published.back(), 19);  // the last pair is never lost
    for (size_t i = 1; i < published.size(); ++i) EXPECT_LT(published[i - 1], published[i]);
  }
}

TEST(StereoDepthWorkerTest, RateLimitAndBadPairs) {
  std::atomic<int> published{0};
  StereoDepthWorker worker(estimator(), 5.0, [&](const CaptureFrame&) { ++published; });
  // 20 Hz frames for one second at 5 Hz at most: frames 0, 4, 8, 12, 16 accepted.
  for (int64_t i = 0; i < 20; ++i) {
    worker.offer(pair(i, i * 50'000'000));
    worker.drain();
  }
  EXPECT_EQ(published.load(), 5);
  EXPECT_EQ(worker.stats().rate_limited, 15u);
  // A pair of another size is counted as failed, not published, and the worker goes on.
  worker.offer(pair(100, 10'000'000'000, 200));
  worker.drain();
  worker.offer(pair(101, 11'000'000'000));
  worker.drain();
  EXPECT_EQ(worker.stats().failed, 1u);
  EXPECT_EQ(published.load(), 6);
}

}  // namespace
}  // namespace cblox
