// The simulator's images must give a feature-based tracker what real images give it: many
// ORB features, spread over the image, that match between the left and right images at the
// disparity the geometry predicts.

#include <algorithm>
#include <cmath>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>

#include "drivers/sim/builtin_scenes.h"
#include "drivers/sim/sim_renderer.h"

namespace cblox {
namespace {

cv::Mat toMat(const GrayImage& image) {
  return cv::Mat(image.height, image.width, CV_8UC1, const_cast<uint8_t*>(image.data.data()))
      .clone();
}

TEST(SimFeaturesTest, EveryBuiltinSceneGivesPlentifulWellSpreadStereoOrbFeatures) {
  for (const std::string& name : builtinSceneNames()) {
    const BuiltinScene scene = makeBuiltinScene(name);
    std::string error;
    std::shared_ptr<const TriangleMeshRaycaster> raycaster =
        TriangleMeshRaycaster::create(scene.mesh, &error);
    ASSERT_NE(raycaster, nullptr) << error;
    SimRendererConfig config;  // 752 x 480, fx 458, baseline 0.11 m
    config.rig.depth_max_m = scene.depth_max_m;
    config.texture.base_wavelength_m = scene.texture_wavelength_m;
    const SimRenderer renderer(raycaster, config);
    const StampedTrajectory trajectory = makeSceneTrajectory(scene, TrajectoryKind::kLoop, 2.0);
    SimImages images;
    renderer.render(trajectory[trajectory.size() / 3].T_G_C, &images);

    cv::Ptr<cv::ORB> orb = cv::ORB::create(3000, 1.2f, 8);
    std::vector<cv::KeyPoint> left_kp, right_kp;
    cv::Mat left_desc, right_desc;
    orb->detectAndCompute(toMat(images.left), cv::noArray(), left_kp, left_desc);
    orb->detectAndCompute(toMat(images.right), cv::noArray(), right_kp, right_desc);
    EXPECT_GT(left_kp.size(), 1000u) << name;
    // Texture everywhere the scene is seen: FAST corners (threshold 7, ORB-SLAM2's fallback)
    // in every cell of a 4 x 4 grid that mostly sees the scene, as a grid-distributed
    // extractor needs.
    const cv::Mat left = toMat(images.left);
    int cells_with_corners = 0, cells_seeing_scene = 0;
    for (int cy = 0; cy < 4; ++cy) {
      for (int cx = 0; cx < 4; ++cx) {
        int valid = 0;
        for (int v = cy * 120; v < (cy + 1) * 120; v += 4) {
          for (int u = cx * 188; u < (cx + 1) * 188; u += 4) valid += images.depth(u, v) > 0.0f;
        }
        if (valid < 0.8 * 30 * 47) continue;  // mostly sky or beyond range
        ++cells_seeing_scene;
        std::vector<cv::KeyPoint> corners;
        cv::FAST(left(cv::Rect(cx * 188, cy * 120, 188, 120)), corners, 7, true);
        cells_with_corners += corners.size() >= 50;
      }
    }
    EXPECT_GE(cells_seeing_scene, 4) << name;
    EXPECT_GE(cells_with_corners * 10, cells_seeing_scene * 9) << name;
    // Left-right matches along rows have the disparity fx * b / z of the true depth.
    cv::BFMatcher matcher(cv::NORM_HAMMING, true);
    std::vector<cv::DMatch> matches;
    matcher.match(left_desc, right_desc, matches);
    int checked = 0, consistent = 0;
    for (const cv::DMatch& m : matches) {
      const cv::Point2f& l = left_kp[m.queryIdx].pt;
      const cv::Point2f& r = right_kp[m.trainIdx].pt;
      if (m.distance > 40 || std::abs(l.y - r.y) > 1.5f) continue;
      const float z = images.depth(static_cast<int>(std::lround(l.x)), static_cast<int>(std::lround(l.y)));
      if (z <= 0.0f) continue;
      ++checked;
      const float predicted = 458.0f * 0.11f / z;
      consistent += std::abs((l.x - r.x) - predicted) < 1.5f;
    }
    EXPECT_GT(checked, 200) << name;
    EXPECT_GT(consistent, checked * 85 / 100) << name << ": " << consistent << " of " << checked;
  }
}

}  // namespace
}  // namespace cblox
