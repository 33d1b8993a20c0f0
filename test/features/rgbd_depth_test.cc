#include "core/features/rgbd_depth.h"

#include <cmath>
#include <limits>
#include <stdexcept>

#include <gtest/gtest.h>

#include "core/features/orb_extractor.h"
#include "test/features/feature_test_frames.h"

namespace cblox {
namespace {

TEST(RgbdDepthTest, VirtualRightCoordinateIsUMinusBfOverZ) {
  const auto& frames = test::simFrames("room", 1);
  ASSERT_FALSE(frames.empty());
  const test::StereoFrame& frame = frames[0];
  OrbExtractor extractor{OrbExtractorConfig{}};
  const ExtractedFeatures f = extractor.extract(frame.left);
  const double bf = frame.fx * frame.baseline_m;
  const StereoDepth depth = depthFromRgbd(f.keypoints, frame.depth, bf);
  ASSERT_EQ(depth.depth.size(), f.keypoints.size());
  ASSERT_EQ(depth.right_u.size(), f.keypoints.size());
  ASSERT_EQ(depth.right_index.size(), f.keypoints.size());
  size_t with_depth = 0;
  for (size_t i = 0; i < f.keypoints.size(); ++i) {
    const Keypoint& kp = f.keypoints[i];
    const float z =
        frame.depth(static_cast<int>(std::lround(kp.u)), static_cast<int>(std::lround(kp.v)));
    EXPECT_EQ(depth.right_index[i], -1);
    if (z > 0.0f) {
      ++with_depth;
      EXPECT_EQ(depth.depth[i], z);
      EXPECT_EQ(depth.right_u[i], static_cast<float>(kp.u - bf / z));
    } else {
      EXPECT_EQ(depth.depth[i], -1.0f);
      EXPECT_EQ(depth.right_u[i], -1.0f);
    }
  }
  EXPECT_EQ(depth.numWithDepth(), with_depth);
  EXPECT_GT(with_depth, 1000u);  // the room is within the rig's depth range
}

TEST(RgbdDepthTest, InvalidOrMissingDepthGivesNoDepth) {
  DepthImage image(8, 6, 2.0f);
  image(1, 1) = 0.0f;
  image(2, 1) = -1.0f;
  image(3, 1) = std::numeric_limits<float>::quiet_NaN();
  image(4, 1) = std::numeric_limits<float>::infinity();
  image(2, 4) = 4.0f;
  const auto at = [](float u, float v) {
    Keypoint kp;
    kp.u = u;
    kp.v = v;
    return kp;
  };
  const std::vector<Keypoint> keypoints = {
      at(1, 1),       at(2, 1),       at(3, 1),    at(4, 1),  // invalid depth values
      at(-0.6f, 2),   at(7.6f, 2),    at(3, 5.5f),            // round to outside the image
      at(2.4f, 3.6f),                                         // rounds to (2, 4)
      at(-0.4f, 0),   at(7.4f, 5.4f),                         // round to the corners
  };
  const StereoDepth depth = depthFromRgbd(keypoints, image, 40.0);
  for (size_t i = 0; i < 7; ++i) {
    EXPECT_EQ(depth.depth[i], -1.0f) << i;
    EXPECT_EQ(depth.right_u[i], -1.0f) << i;
  }
  EXPECT_EQ(depth.depth[7], 4.0f);
  EXPECT_EQ(depth.right_u[7], 2.4f - 10.0f);  // 40 / 4
  EXPECT_EQ(depth.depth[8], 2.0f);
  EXPECT_EQ(depth.right_u[8], -0.4f - 20.0f);  // negative right_u with depth: a valid value
  EXPECT_EQ(depth.depth[9], 2.0f);
  EXPECT_EQ(depth.numWithDepth(), 3u);
  EXPECT_TRUE(depthFromRgbd({}, image, 40.0).depth.empty());
}

TEST(RgbdDepthTest, RejectsBadInputsWithAMessage) {
  const std::vector<Keypoint> keypoints(3);
  const auto error = [&](const DepthImage& image, double bf) {
    try {
      depthFromRgbd(keypoints, image, bf);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(error(DepthImage(), 40.0).find("empty"), std::string::npos);
  DepthImage broken(10, 10, 1.0f);
  broken.data.resize(20);
  EXPECT_NE(error(broken, 40.0).find("pixels"), std::string::npos);
  const DepthImage fine(10, 10, 1.0f);
  EXPECT_NE(error(fine, 0.0).find("bf"), std::string::npos);
  EXPECT_NE(error(fine, -3.0).find("bf"), std::string::npos);
  EXPECT_NE(error(fine, std::numeric_limits<double>::infinity()).find("bf"), std::string::npos);
  EXPECT_EQ(error(fine, 40.0), "no error");
}

}  // namespace
}  // namespace cblox
