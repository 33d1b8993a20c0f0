#include "drivers/sim/sim_renderer.h"

#include <cmath>
#include <cstdlib>
#include <vector>

#include <gtest/gtest.h>

#include "core/mesh/primitive_meshes.h"

namespace cblox {
namespace {

const Color kWhite{230, 230, 230};

std::shared_ptr<const TriangleMeshRaycaster> build(const Mesh& mesh) {
  std::string error;
  std::shared_ptr<const TriangleMeshRaycaster> scene = TriangleMeshRaycaster::create(mesh, &error);
  EXPECT_NE(scene, nullptr) << error;
  return scene;
}

SimRendererConfig smallRig() {
  SimRendererConfig config;
  config.rig.stereo = PinholeIntrinsics{400.0, 400.0, 159.5, 119.5, 320, 240};
  config.rig.baseline_m = 0.1;
  config.rig.depth_max_m = 50.0;
  return config;
}

/// A large wall in the plane z = distance, facing the camera at the origin.
Mesh wallAt(float distance) {
  Mesh mesh;
  appendQuad(&mesh, Eigen::Vector3f(-20, -20, distance), Eigen::Vector3f(0, 40, 0),
             Eigen::Vector3f(40, 0, 0), kWhite);
  return mesh;
}

TEST(SimRendererTest, FrontoParallelPlaneHasExactDepthEverywhere) {
  const SimRenderer renderer(build(wallAt(2.5f)), smallRig());
  SimImages images;
  renderer.render(Transformationd::Identity(), &images);
  ASSERT_EQ(images.depth.width, 320);
  ASSERT_EQ(images.depth.height, 240);
  for (float d : images.depth.data) ASSERT_FLOAT_EQ(d, 2.5f);
  EXPECT_EQ(images.left.width, 320);
  EXPECT_EQ(images.right.height, 240);
  EXPECT_EQ(images.color.width, 320);
}

TEST(SimRendererTest, RendersIntoMovedFromImages) {
  // A caller that moves the images out (e.g. into a list of frames) and renders again into
  // the same object gets fresh, complete images: width and height survive a move, pixels not.
  const SimRenderer renderer(build(wallAt(2.5f)), smallRig());
  SimImages images;
  renderer.render(Transformationd::Identity(), &images);
  std::vector<SimImages> kept;
  kept.push_back(std::move(images));
  renderer.render(Transformationd::Identity(), &images);
  ASSERT_EQ(images.depth.data.size(), 320u * 240u);
  ASSERT_EQ(images.left.data.size(), 320u * 240u);
  ASSERT_EQ(images.right.data.size(), 320u * 240u);
  ASSERT_EQ(images.color.data.size(), 320u * 240u);
  for (float d : images.depth.data) ASSERT_FLOAT_EQ(d, 2.5f);
  EXPECT_EQ(images.left.data, kept[0].left.data);
}

TEST(SimRendererTest, TiltedPlaneDepthMatchesAnalyticRayPlaneIntersection) {
  // Plane through (0, 0, 3) with normal n = (0.3, -0.2, -1): n . X = n . (0, 0, 3).
  const Eigen::Vector3d n(0.3, -0.2, -1.0);
  const double c = n.dot(Eigen::Vector3d(0, 0, 3));
  const Eigen::Vector3d e1 = n.cross(Eigen::Vector3d::UnitX()).normalized();
  const Eigen::Vector3d e2 = n.normalized().cross(e1);
  Mesh mesh;
  const Eigen::Vector3d corner = Eigen::Vector3d(0, 0, 3) - 20 * e1 - 20 * e2;
  appendQuad(&mesh, corner.cast<float>(), (40 * e1).cast<float>(), (40 * e2).cast<float>(), kWhite);
  // The camera is rotated and moved: compare in the camera frame.
  const Transformationd T_G_C(
      Eigen::Quaterniond(Eigen::AngleAxisd(0.1, Eigen::Vector3d(1, 1, 0).normalized())),
      Eigen::Vector3d(0.2, -0.1, 0.3));
  const SimRenderer renderer(build(mesh), smallRig());
  DepthImage depth;
  const PinholeIntrinsics& K = renderer.config().rig.stereo;
  renderer.renderView(T_G_C, K, nullptr, nullptr, &depth);
  const Eigen::Vector3d n_C = T_G_C.rotation().inverse() * n;
  const double c_C = c - n.dot(T_G_C.translation());
  double worst = 0.0;
  for (int v = 0; v < K.height; v += 7) {
    for (int u = 0; u < K.width; u += 5) {
      const Eigen::Vector3d ray((u - K.cx) / K.fx, (v - K.cy) / K.fy, 1.0);
      const double z = c_C / n_C.dot(ray);
      worst = std::max(worst, std::abs(depth(u, v) - z) / z);
    }
  }
  EXPECT_LT(worst, 2e-6);  // float precision
}

TEST(SimRendererTest, BoxAtKnownPoseAndDepthRangeLimits) {
  Mesh mesh;
  appendBox(&mesh, Eigen::AlignedBox3f(Eigen::Vector3f(-0.5f, -0.5f, 4.0f),
                                       Eigen::Vector3f(0.5f, 0.5f, 5.0f)),
            kWhite);
  SimRendererConfig config = smallRig();
  config.rig.depth_max_m = 4.5;
  const SimRenderer renderer(build(mesh), config);
  SimImages images;
  // Move the rig 1 m back: the front face is 5 m away, beyond the 4.5 m range.
  renderer.render(Transformationd(Eigen::Quaterniond::Identity(), Eigen::Vector3d(0, 0, -1)),
                  &images);
  EXPECT_EQ(images.depth(160, 120), 0.0f);
  renderer.render(Transformationd::Identity(), &images);
  EXPECT_FLOAT_EQ(images.depth(160, 120), 4.0f);  // 4 ulps: Embree rounds per ISA
  // Box edge: x = 0.5 at z = 4 projects to u = 159.5 + 400 * 0.125 = 209.5.
  EXPECT_FLOAT_EQ(images.depth(209, 120), 4.0f);
  EXPECT_EQ(images.depth(210, 120), 0.0f);  // sees past the box: nothing
  EXPECT_EQ(images.left(210, 120), renderer.config().lighting.background_gray);
}

TEST(SimRendererTest, StereoPairHasDisparityFocalTimesBaselineOverDepth) {
  // fx * b / z = 400 * 0.1 / 2.5 = 16 px.
  const SimRenderer renderer(build(wallAt(2.5f)), smallRig());
  SimImages images;
  renderer.render(Transformationd::Identity(), &images);
  // The texture has content.
  double mean = 0, mean2 = 0;
  for (uint8_t g : images.left.data) mean += g, mean2 += g * g;
  mean /= images.left.data.size();
  const double stddev = std::sqrt(mean2 / images.left.data.size() - mean * mean);
  EXPECT_GT(stddev, 15.0);
  // Block matching along rows finds 16 px for nearly every patch.
  int patches = 0, exact = 0;
  for (int v = 10; v < 230; v += 12) {
    for (int u = 60; u < 310; u += 12) {
      int best_d = -1;
      long best_sad = -1;
      for (int d = 0; d <= 40; ++d) {
        long sad = 0;
        for (int dv = -4; dv <= 4; ++dv) {
          for (int du = -4; du <= 4; ++du) {
            sad += std::abs(images.left(u + du, v + dv) - images.right(u + du - d, v + dv));
          }
        }
        if (best_sad < 0 || sad < best_sad) best_sad = sad, best_d = d;
      }
      ++patches;
      exact += best_d == 16;
    }
  }
  EXPECT_GE(exact, patches * 98 / 100) << exact << " of " << patches;
  // Pixel-wise: right(u - 16, v) sees the same surface point as left(u, v).
  int same = 0, total = 0;
  for (int v = 0; v < 240; ++v) {
    for (int u = 16; u < 320; ++u) {
      ++total;
      same += std::abs(images.left(u, v) - images.right(u - 16, v)) <= 1;
    }
  }
  EXPECT_GE(same, total * 99 / 100);
}

TEST(SimRendererTest, RightPrincipalPointErrorLowersEveryDisparityByIt) {
  // A calibration error of 3 px: the right image is rendered with cx + 3, the published
  // calibration keeps cx, and the disparity of the wall becomes 16 - 3 = 13 px everywhere.
  SimRendererConfig config = smallRig();
  config.rig.right_cx_error_px = 3.0;
  EXPECT_EQ(config.rig.stereoCalibration().intrinsics.cx, 159.5);
  EXPECT_EQ(config.rig.rightIntrinsics().cx, 162.5);
  const SimRenderer renderer(build(wallAt(2.5f)), config);
  SimImages images;
  renderer.render(Transformationd::Identity(), &images);
  int same13 = 0, same16 = 0, total = 0;
  for (int v = 0; v < 240; ++v) {
    for (int u = 16; u < 320; ++u) {
      ++total;
      same13 += std::abs(images.left(u, v) - images.right(u - 13, v)) <= 1;
      same16 += std::abs(images.left(u, v) - images.right(u - 16, v)) <= 1;
    }
  }
  EXPECT_GE(same13, total * 99 / 100);
  EXPECT_LT(same16, total / 2);
  config.rig.right_cx_error_px = -10.5;
  EXPECT_THROW(SimRenderer(build(wallAt(2.5f)), config), std::invalid_argument);
}

TEST(SimRendererTest, DepthCameraWithExtrinsicsRendersItsOwnView) {
  SimRendererConfig config = smallRig();
  config.rig.depth = PinholeIntrinsics{200.0, 200.0, 79.5, 59.5, 160, 120};
  // Depth camera 0.5 m further from the wall than the left camera.
  config.rig.T_L_D = Transformationd(Eigen::Quaterniond::Identity(), Eigen::Vector3d(0.05, 0, -0.5));
  ASSERT_FALSE(config.rig.depthIsLeftCamera());
  const SimRenderer renderer(build(wallAt(2.5f)), config);
  SimImages images;
  renderer.render(Transformationd::Identity(), &images);
  ASSERT_EQ(images.depth.width, 160);
  ASSERT_EQ(images.color.width, 160);
  ASSERT_EQ(images.left.width, 320);
  for (float d : images.depth.data) ASSERT_FLOAT_EQ(d, 3.0f);
}

TEST(SimRendererTest, RejectsInvalidConfig) {
  SimRendererConfig config = smallRig();
  config.rig.baseline_m = 0.0;
  EXPECT_THROW(SimRenderer(build(wallAt(1.0f)), config), std::invalid_argument);
  config = smallRig();
  config.rig.depth_max_m = 0.05;
  try {
    SimRenderer renderer(build(wallAt(1.0f)), config);
    FAIL() << "expected an exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("depth range"), std::string::npos) << e.what();
  }
  EXPECT_THROW(SimRenderer(nullptr, smallRig()), std::invalid_argument);
}

}  // namespace
}  // namespace cblox
