// Our orientation and rotated BRIEF against OpenCV's ORB: the same angles for the same
// keypoints, and bit-identical descriptors for the same keypoint, angle and level image.

#include <sys/mman.h>
#include <unistd.h>

#include <random>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/features2d.hpp>

#include "core/features/orb_extractor.h"
#include "core/features/orb_orientation.h"
#include "core/features/orb_pattern.h"
#include "core/features/rotated_brief.h"
#include "test/features/feature_test_frames.h"

namespace cblox {
namespace {

using test::matView;
using test::simFrames;

// OpenCV's ORB on one level image: single level, our border, the standard 31x31 pattern.
cv::Ptr<cv::ORB> singleLevelOrb() {
  return cv::ORB::create(5000, 1.2f, 1, OrbExtractorConfig::kEdgeThreshold, 0, 2,
                         cv::ORB::FAST_SCORE, OrbExtractorConfig::kPatchSize, 20);
}

TEST(OrbPatternTest, IsOpenCvsLearnedPatternWithinTheBriefRadius) {
  const auto& pattern = orbPattern31();
  // Spot checks against OpenCV's bit_pattern_31_ (first, a middle and the last pair).
  EXPECT_EQ(pattern[0].a.x, 8);
  EXPECT_EQ(pattern[0].a.y, -3);
  EXPECT_EQ(pattern[0].b.x, 9);
  EXPECT_EQ(pattern[0].b.y, 5);
  EXPECT_EQ(pattern[255].a.x, -1);
  EXPECT_EQ(pattern[255].a.y, -6);
  EXPECT_EQ(pattern[255].b.x, 0);
  EXPECT_EQ(pattern[255].b.y, -11);
  for (const OrbPointPair& p : pattern) {
    for (const OrbPointPair::Point& q : {p.a, p.b}) {
      EXPECT_GE(q.x, -13);
      EXPECT_LE(q.x, 12);
      EXPECT_GE(q.y, -13);
      EXPECT_LE(q.y, 12);
      EXPECT_LT(q.x * q.x + q.y * q.y, kRotatedBriefRadius * kRotatedBriefRadius);
    }
  }
}

TEST(OrbOrientationTest, UmaxIsOpenCvsSymmetricCircleOfRadius15) {
  const OrbOrientation orientation;
  const std::array<int, 16> expected = {15, 15, 15, 15, 14, 14, 14, 13, 13, 12, 11, 10, 9, 8, 6, 3};
  EXPECT_EQ(orientation.umax(), expected);
}

// Our angle of each keypoint OpenCV's ORB finds on `image` is OpenCV's; returns how many.
size_t expectAnglesOfOpenCvOrb(const cv::Mat& image) {
  std::vector<cv::KeyPoint> keypoints;
  singleLevelOrb()->detect(image, keypoints);
  const OrbOrientation orientation;
  for (const cv::KeyPoint& kp : keypoints) {
    const float angle = orientation.angleDeg(image, cvRound(kp.pt.x), cvRound(kp.pt.y));
    EXPECT_EQ(angle, kp.angle) << kp.pt;
    if (angle != kp.angle) break;
  }
  return keypoints.size();
}

TEST(OrbOrientationTest, AnglesEqualOpenCvOrbsOnItsOwnKeypoints) {
  const auto& frames = simFrames("room", 1);
  ASSERT_FALSE(frames.empty());
  EXPECT_GT(expectAnglesOfOpenCvOrb(matView(frames[0].left)), 1000u);
}

TEST(OrbOrientationTest, AnglesEqualOpenCvOrbsOnSaturatedNoise) {
  // Pixels of 0 and 255 only: the largest moments the sums can meet.
  cv::Mat image(240, 320, CV_8UC1);
  cv::randu(image, 0, 2);
  image *= 255;
  EXPECT_GT(expectAnglesOfOpenCvOrb(image), 100u);
}

// Computes OpenCV's descriptors of `ours` (keypoints of one level, level coordinates) on the
// level image and checks that OpenCV keeps every keypoint, position and angle unchanged.
cv::Mat openCvDescriptors(const cv::Mat& level, const std::vector<cv::KeyPoint>& ours) {
  std::vector<cv::KeyPoint> keypoints = ours;
  cv::Mat descriptors;
  singleLevelOrb()->compute(level, keypoints, descriptors);
  EXPECT_EQ(keypoints.size(), ours.size());
  if (keypoints.size() != ours.size()) return {};
  for (size_t i = 0; i < ours.size(); ++i) {
    EXPECT_EQ(keypoints[i].pt, ours[i].pt);
    EXPECT_EQ(keypoints[i].angle, ours[i].angle);
  }
  return descriptors;
}

TEST(RotatedBriefTest, ExtractorDescriptorsAreBitIdenticalToOpenCvOrbOnEveryLevel) {
  const auto& frames = simFrames("room", 1);
  ASSERT_FALSE(frames.empty());
  OrbExtractor extractor{OrbExtractorConfig{}};
  const ExtractedFeatures f = extractor.extract(frames[0].left);
  ASSERT_GT(f.keypoints.size(), 1000u);
  size_t compared = 0;
  for (int level = 0; level < f.scales.numLevels(); ++level) {
    std::vector<cv::KeyPoint> ours;
    std::vector<size_t> index;
    for (size_t i = 0; i < f.keypoints.size(); ++i) {
      const Keypoint& kp = f.keypoints[i];
      if (kp.octave != level) continue;
      const float s = f.scales.invScale(level);
      // Level coordinates are integers; recover them from the level-0 ones.
      ours.emplace_back(static_cast<float>(cvRound(kp.u * s)),
                        static_cast<float>(cvRound(kp.v * s)), 31.0f, kp.angle_deg, kp.response, 0);
      index.push_back(i);
    }
    ASSERT_FALSE(ours.empty()) << "level " << level;
    const cv::Mat descriptors = openCvDescriptors(f.pyramid[static_cast<size_t>(level)], ours);
    ASSERT_EQ(descriptors.rows, static_cast<int>(ours.size()));
    for (size_t k = 0; k < ours.size(); ++k) {
      ASSERT_EQ(f.descriptors[index[k]],
                OrbDescriptor::fromBytes(descriptors.ptr<uint8_t>(static_cast<int>(k))))
          << "level " << level << " keypoint " << k;
      ++compared;
    }
  }
  EXPECT_EQ(compared, f.keypoints.size());
}

TEST(RotatedBriefTest, BitIdenticalToOpenCvOrbAtRandomAngles) {
  // Every angle, including multiples of 45 and 90 degrees where rounding ties occur.
  const auto& frames = simFrames("room", 1);
  ASSERT_FALSE(frames.empty());
  const cv::Mat image = matView(frames[0].left);
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> angle(0.0f, 360.0f);
  std::uniform_int_distribution<int> u(19, image.cols - 20), v(19, image.rows - 20);
  std::vector<cv::KeyPoint> keypoints;
  for (int i = 0; i < 4000; ++i) {
    const float a = i < 360   ? static_cast<float>(i)
                    : i < 400 ? 45.0f * static_cast<float>(i % 8)
                              : angle(rng);
    keypoints.emplace_back(static_cast<float>(u(rng)), static_cast<float>(v(rng)), 31.0f, a);
  }
  const cv::Mat descriptors = openCvDescriptors(image, keypoints);
  ASSERT_EQ(descriptors.rows, static_cast<int>(keypoints.size()));
  BriefBlur blur;
  cv::Mat blurred;
  blur.apply(image, &blurred);
  const RotatedBrief brief;
  for (size_t k = 0; k < keypoints.size(); ++k) {
    const cv::KeyPoint& kp = keypoints[k];
    const OrbDescriptor expected =
        OrbDescriptor::fromBytes(descriptors.ptr<uint8_t>(static_cast<int>(k)));
    // compute() takes the AVX2 path on CPUs that have it; computePortable() never does.
    ASSERT_EQ(brief.compute(blurred, kp.pt.x, kp.pt.y, kp.angle), expected)
        << "keypoint " << k << " at " << kp.pt << " angle " << kp.angle;
    ASSERT_EQ(brief.computePortable(blurred, kp.pt.x, kp.pt.y, kp.angle), expected)
        << "keypoint " << k << " at " << kp.pt << " angle " << kp.angle;
  }
}

TEST(RotatedBriefTest, KeypointsOnTheAllowedBorderReadNothingPastTheImage) {
  // The AVX2 path reads a 32-bit word at every sample point. Put the image's last byte just
  // before an unreadable page: keypoints kRotatedBriefRadius pixels from the border, at every
  // angle, must neither fault nor differ from the portable path.
  constexpr int kWidth = 61, kHeight = 40;  // an odd width: rows are not word-aligned
  const size_t page = static_cast<size_t>(sysconf(_SC_PAGESIZE));
  const size_t bytes = static_cast<size_t>(kWidth) * kHeight;
  const size_t span = (bytes + page - 1) / page * page;
  void* region =
      mmap(nullptr, span + page, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
  ASSERT_NE(region, MAP_FAILED);
  ASSERT_EQ(mprotect(static_cast<uint8_t*>(region) + span, page, PROT_NONE), 0);
  uint8_t* data = static_cast<uint8_t*>(region) + span - bytes;
  std::mt19937 rng(3);
  for (size_t i = 0; i < bytes; ++i) data[i] = static_cast<uint8_t>(rng() & 0xFF);
  const cv::Mat image(kHeight, kWidth, CV_8UC1, data);
  const RotatedBrief brief;
  constexpr int r = kRotatedBriefRadius;
  size_t distinct = 0;
  OrbDescriptor previous;
  for (const int y : {r, kHeight - 1 - r}) {
    for (const int x : {r, kWidth - 1 - r}) {
      for (int degrees = 0; degrees < 360; ++degrees) {
        const float angle = static_cast<float>(degrees);
        const OrbDescriptor d =
            brief.compute(image, static_cast<float>(x), static_cast<float>(y), angle);
        ASSERT_EQ(d,
                  brief.computePortable(image, static_cast<float>(x), static_cast<float>(y), angle))
            << "keypoint (" << x << ", " << y << ") angle " << degrees;
        if (!(d == previous)) ++distinct;
        previous = d;
      }
    }
  }
  EXPECT_GT(distinct, 1000u);  // the descriptors change with angle and place: real tests
  munmap(region, span + page);
}

}  // namespace
}  // namespace cblox
