#include "core/eval/distance_field_accuracy.h"

#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "core/mesh/primitive_meshes.h"

namespace cblox {
namespace {

const Color kGrey{128, 128, 128};

// A solid unit cube [0, 1]^3 inside a room [-3, 3] x [-6, 6] x [-5, 6] seen from inside (its
// walls' normals point into the room, so the space beyond them is solid).
std::unique_ptr<TriangleMeshRaycaster> cubeInRoom() {
  Mesh mesh;
  appendBox(&mesh, Eigen::AlignedBox3f(Eigen::Vector3f(0, 0, 0), Eigen::Vector3f(1, 1, 1)), kGrey);
  appendBox(&mesh, Eigen::AlignedBox3f(Eigen::Vector3f(-3, -6, -5), Eigen::Vector3f(3, 6, 6)),
            kGrey, /*inward=*/true);
  std::string error;
  auto raycaster = TriangleMeshRaycaster::create(mesh, &error);
  EXPECT_NE(raycaster, nullptr) << error;
  return raycaster;
}

// A 64 x 64 camera at (-2, 0.5, 0.5) looking along +x (x right = -y, y down = -z), 90 degrees
// across, depths 0.1 to 3 m.
DepthView lookingAtTheCube() {
  DepthView view;
  Eigen::Matrix3d R_G_D;
  R_G_D.col(0) = Eigen::Vector3d(0, -1, 0);
  R_G_D.col(1) = Eigen::Vector3d(0, 0, -1);
  R_G_D.col(2) = Eigen::Vector3d(1, 0, 0);
  view.T_G_D = Transformationd(R_G_D, Eigen::Vector3d(-2, 0.5, 0.5));
  view.intrinsics = PinholeIntrinsics{32.0, 32.0, 32.0, 32.0, 64, 64};
  view.min_depth_m = 0.1;
  view.max_depth_m = 3.0;
  return view;
}

TEST(DistanceFieldAccuracyTest, SignedDistancesAreExactAndNegativeInsideSolids) {
  const auto truth = cubeInRoom();
  EXPECT_NEAR(signedDistanceToMesh(*truth, Eigen::Vector3d(0.5, 0.5, 0.5)), -0.5, 1e-9);
  EXPECT_NEAR(signedDistanceToMesh(*truth, Eigen::Vector3d(0.5, 0.5, 0.8)), -0.2, 1e-9);
  EXPECT_NEAR(signedDistanceToMesh(*truth, Eigen::Vector3d(1.5, 0.5, 0.5)), 0.5, 1e-9);
  // Beside an edge: the distance to the edge, outside.
  EXPECT_NEAR(signedDistanceToMesh(*truth, Eigen::Vector3d(1.3, 1.4, 0.5)), 0.5, 1e-9);
  // Behind the room's wall: inside its solid.
  EXPECT_NEAR(signedDistanceToMesh(*truth, Eigen::Vector3d(3.25, 0.0, 1.0)), -0.25, 1e-9);
}

TEST(DistanceFieldAccuracyTest, ObservedFreeIsWhatTheViewSawThroughBeyondTheTruncation) {
  const auto truth = cubeInRoom();
  const DepthView view = lookingAtTheCube();
  DistanceTruthConfig config;
  config.samples = 4000;
  config.box =
      Eigen::AlignedBox3d(Eigen::Vector3d(-2.9, -2.9, -0.9), Eigen::Vector3d(2.9, 2.9, 2.9));
  config.truncation_m = 0.2;
  config.free_margin_m = 0.05;
  std::string error;
  const auto samples =
      sampleDistanceTruth(*truth, std::span<const DepthView>(&view, 1), config, &error);
  ASSERT_TRUE(samples) << error;
  ASSERT_EQ(samples->size(), 4000u);
  // Each sample's verdict, recomputed by hand: in the frustum, in depth range, the surface on
  // its ray (the cube's face x = 0 or a wall) at least 0.25 m deeper.
  size_t free = 0;
  for (const DistanceTruthSample& s : *samples) {
    EXPECT_TRUE(config.box.contains(s.p_G));
    EXPECT_EQ(s.signed_distance_m, signedDistanceToMesh(*truth, s.p_G));
    const Eigen::Vector3d p_D = view.T_G_D.inverse() * s.p_G;
    const double z = p_D.z();
    const bool in_view = z >= 0.1 && z <= 3.0 && std::abs(p_D.x()) < z && std::abs(p_D.y()) < z;
    // Where the ray through p ends: the cube's face at depth 2 when the ray crosses it, else
    // a wall at depth 5 or more (beyond the 3 m range: nothing measured).
    const Eigen::Vector3d on_face = p_D / z * 2.0;  // the ray at depth 2, in D
    const bool hits_cube = std::abs(on_face.x()) < 0.5 && std::abs(on_face.y()) < 0.5;
    const bool expected = in_view && hits_cube && 2.0 - z >= 0.25 && s.signed_distance_m > 0;
    // Points within a millimetre of the frustum's or the face's edges are left alone.
    const bool borderline = std::abs(std::abs(on_face.x()) - 0.5) < 1e-3 ||
                            std::abs(std::abs(on_face.y()) - 0.5) < 1e-3 ||
                            std::abs(2.0 - z - 0.25) < 1e-3;
    if (!borderline) {
      EXPECT_EQ(s.observed_free, expected) << s.p_G.transpose();
    }
    if (s.observed_free) ++free;
  }
  // The pyramid from the camera to the face up to depth 1.75 (0.45 m^3) is 0.35 % of the
  // box: about 14 points.
  EXPECT_GT(free, 0u);
  EXPECT_LT(free, 40u);
  // Same seed, same samples; another thread count, same verdicts.
  config.num_threads = 1;
  const auto again =
      sampleDistanceTruth(*truth, std::span<const DepthView>(&view, 1), config, &error);
  ASSERT_TRUE(again);
  for (size_t i = 0; i < samples->size(); ++i) {
    EXPECT_EQ((*again)[i].p_G, (*samples)[i].p_G);
    EXPECT_EQ((*again)[i].observed_free, (*samples)[i].observed_free);
  }
}

TEST(DistanceFieldAccuracyTest, TheNearestSurfaceIsSeenWhenTheViewSawItsClosestPoint) {
  const auto truth = cubeInRoom();
  const DepthView view = lookingAtTheCube();
  DepthView near_view = view;
  auto at = [&](const Eigen::Vector3d& p) {
    DistanceTruthConfig config;
    config.samples = 1;
    config.box = Eigen::AlignedBox3d(p - Eigen::Vector3d::Constant(1e-9),
                                     p + Eigen::Vector3d::Constant(1e-9));
    config.truncation_m = 0.2;
    std::string error;
    const auto samples =
        sampleDistanceTruth(*truth, std::span<const DepthView>(&near_view, 1), config, &error);
    EXPECT_TRUE(samples) << error;
    return samples ? samples->front() : DistanceTruthSample{};
  };
  // In front of the face x = 0 the camera looks at: its closest point is on that face.
  const DistanceTruthSample front = at(Eigen::Vector3d(-0.5, 0.5, 0.5));
  EXPECT_NEAR(front.signed_distance_m, 0.5, 1e-6);
  EXPECT_TRUE(front.observed_free);
  EXPECT_TRUE(front.nearest_surface_seen);
  // Behind the cube: its closest point is on the back face x = 1, hidden from the camera.
  const DistanceTruthSample behind = at(Eigen::Vector3d(1.3, 0.5, 0.5));
  EXPECT_NEAR(behind.signed_distance_m, 0.3, 1e-6);
  EXPECT_FALSE(behind.observed_free);
  EXPECT_FALSE(behind.nearest_surface_seen);
  // A camera that integrates nothing farther than 1.9 m along the ray measured neither the
  // face 2 m away nor the space in front of it.
  near_view.max_ray_length_m = 1.9;
  const DistanceTruthSample unmeasured = at(Eigen::Vector3d(-0.5, 0.5, 0.5));
  EXPECT_FALSE(unmeasured.observed_free);
  EXPECT_FALSE(unmeasured.nearest_surface_seen);
}

TEST(DistanceFieldAccuracyTest, BadOptionsAreRefused) {
  const auto truth = cubeInRoom();
  DistanceTruthConfig config;
  config.box = Eigen::AlignedBox3d(Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, 1, 1));
  std::string error;
  config.view_stride = 0;
  EXPECT_FALSE(sampleDistanceTruth(*truth, {}, config, &error));
  EXPECT_NE(error.find("view_stride"), std::string::npos);
  config.view_stride = 1;
  config.box = Eigen::AlignedBox3d();  // empty
  EXPECT_FALSE(sampleDistanceTruth(*truth, {}, config, &error));
  EXPECT_NE(error.find("box"), std::string::npos);
}

TEST(DistanceFieldAccuracyTest, TheFiguresCountWhatAPlannerWouldMeet) {
  constexpr double kVoxel = 0.1;
  auto sample = [](double d, bool observed_free, bool seen = true) {
    DistanceTruthSample s;
    s.signed_distance_m = d;
    s.observed_free = observed_free;
    s.nearest_surface_seen = seen;
    return s;
  };
  const std::vector<DistanceTruthSample> truth = {
      sample(-0.05, false, false),  // inside, answered free 0.2: unsafe; its surface unseen
      sample(0.05, false),          // near, answered free 0.1005: within 1 % of a voxel, safe
      sample(0.09, false),          // near, answered free 0.15: unsafe by less than a voxel
      sample(0.08, false),          // near, answered occupied -0.02
      sample(0.5, true),            // observed free, answered 0.45
      sample(0.9, true),            // observed free, answered unknown
      sample(3.0, true),            // beyond max distance, answered occupied: a false obstacle
  };
  const std::vector<FieldAnswer> answers = {
      {VoxelState::kFree, 0.2},       {VoxelState::kFree, 0.1005}, {VoxelState::kFree, 0.15},
      {VoxelState::kOccupied, -0.02}, {VoxelState::kFree, 0.45},   {VoxelState::kUnknown, 0.0},
      {VoxelState::kOccupied, -0.05},
  };
  const DistanceFieldAccuracy a = scoreDistanceField(truth, answers, kVoxel, 2.0);
  EXPECT_EQ(a.samples, 7u);
  EXPECT_EQ(a.answered_free, 4u);
  EXPECT_EQ(a.answered_occupied, 2u);
  EXPECT_EQ(a.answered_unknown, 1u);
  EXPECT_EQ(a.near_obstacle, 4u);
  EXPECT_EQ(a.unsafe, 2u);
  EXPECT_EQ(a.unsafe_by_a_voxel, 1u);
  EXPECT_EQ(a.unsafe_seen, 1u);  // the point at 0.09; the one inside is beside an unseen face
  EXPECT_EQ(a.unsafe_seen_by_a_voxel, 0u);
  EXPECT_EQ(a.observed_free, 3u);
  EXPECT_EQ(a.observed_free_unknown, 1u);
  EXPECT_EQ(a.far_answered_occupied, 1u);
  // Errors (voxels) of the five known answers within 2 - 0.1 m: 2.5, 0.505, 0.6, 1.0, 0.5.
  EXPECT_EQ(a.compared, 5u);
  EXPECT_NEAR(a.error_median_voxels, 0.6, 1e-9);  // the upper median
  EXPECT_NEAR(a.error_p99_voxels, 2.5, 1e-9);
  EXPECT_NEAR(a.error_max_voxels, 2.5, 1e-9);
  // Without the point whose nearest surface no view saw: 0.505, 0.6, 1.0, 0.5.
  EXPECT_EQ(a.compared_seen, 4u);
  EXPECT_NEAR(a.seen_error_median_voxels, 0.6, 1e-9);
  EXPECT_NEAR(a.seen_error_p99_voxels, 1.0, 1e-9);
  EXPECT_NEAR(a.seen_error_max_voxels, 1.0, 1e-9);
  EXPECT_THROW(
      scoreDistanceField(truth, std::span<const FieldAnswer>(answers).first(2), kVoxel, 2.0),
      std::invalid_argument);
}

}  // namespace
}  // namespace cblox
