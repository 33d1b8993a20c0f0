#include "drivers/sim/builtin_scenes.h"

#include <cmath>

#include <gtest/gtest.h>

#include "core/mesh/mesh_topology.h"
#include "core/raycast/triangle_mesh_raycaster.h"

namespace cblox {
namespace {

TEST(BuiltinScenesTest, EverySceneIsAValidManifoldMeshOfTheAnnouncedSize) {
  struct Expect {
    const char* name;
    Eigen::Vector3f min_size, max_size;
  };
  const Expect expects[] = {{"room", {4.9f, 6.4f, 2.6f}, {5.1f, 6.6f, 2.8f}},
                            {"hall", {39.9f, 19.9f, 9.9f}, {40.1f, 20.1f, 10.1f}},
                            {"town", {260.0f, 260.0f, 10.0f}, {270.0f, 270.0f, 25.0f}},
                            {"yard", {30.7f, 30.7f, 3.9f}, {30.9f, 30.9f, 4.1f}}};
  for (const Expect& e : expects) {
    const BuiltinScene scene = makeBuiltinScene(e.name);
    EXPECT_EQ(scene.name, e.name);
    EXPECT_TRUE(scene.mesh.validate().empty()) << e.name;
    EXPECT_TRUE(scene.mesh.hasColors());
    EXPECT_GT(scene.mesh.numTriangles(), 500u) << e.name;
    const MeshTopology topology = analyzeTopology(scene.mesh);
    EXPECT_TRUE(topology.manifold()) << e.name << ": " << topology.summary();
    EXPECT_EQ(topology.misoriented_edges, 0u) << e.name;
    EXPECT_EQ(topology.degenerate_triangles, 0u) << e.name;
    Eigen::AlignedBox3f bounds;
    for (const auto& v : scene.mesh.vertices) bounds.extend(v);
    const Eigen::Vector3f size = bounds.sizes();
    EXPECT_TRUE((size.array() >= e.min_size.array()).all()) << e.name << " " << size.transpose();
    EXPECT_TRUE((size.array() <= e.max_size.array()).all()) << e.name << " " << size.transpose();
  }
  EXPECT_THROW(makeBuiltinScene("moon"), std::invalid_argument);
}

TEST(BuiltinScenesTest, ScenesAreDeterministic) {
  const BuiltinScene a = makeTown(), b = makeTown();
  ASSERT_EQ(a.mesh.numVertices(), b.mesh.numVertices());
  for (size_t i = 0; i < a.mesh.numVertices(); i += 97) {
    EXPECT_EQ(a.mesh.vertices[i], b.mesh.vertices[i]);
  }
}

/// The smallest distance from a pose of `trajectory` to `raycaster`'s mesh, metres.
double closestApproach(const TriangleMeshRaycaster& raycaster,
                       const StampedTrajectory& trajectory) {
  double closest = 1e9;
  for (const StampedPose& pose : trajectory) {
    closest = std::min(closest, raycaster.closestPoint(pose.T_G_C.translation()).distance);
  }
  return closest;
}

/// `kind` is parsed from `text`, and the scenes other than the town have no such route.
void expectTownOnly(const char* text, TrajectoryKind kind) {
  EXPECT_EQ(parseTrajectoryKind(text), kind);
  for (const char* name : {"room", "hall", "yard"}) {
    EXPECT_THROW(makeSceneTrajectory(makeBuiltinScene(name), kind, 10.0), std::invalid_argument)
        << name;
  }
}

TEST(BuiltinScenesTest, EveryTrajectoryKeepsClearOfTheScene) {
  for (const std::string& name : builtinSceneNames()) {
    const BuiltinScene scene = makeBuiltinScene(name);
    std::string error;
    const auto raycaster = TriangleMeshRaycaster::create(scene.mesh, &error);
    ASSERT_NE(raycaster, nullptr) << error;
    const double clearance = name == "room" ? 0.25 : 0.8;
    for (TrajectoryKind kind : {TrajectoryKind::kLoop, TrajectoryKind::kOrbit,
                                TrajectoryKind::kLawnMower, TrajectoryKind::kFigureEight}) {
      const StampedTrajectory trajectory = makeSceneTrajectory(scene, kind, 10.0);
      ASSERT_GT(trajectory.size(), 20u) << name;
      EXPECT_GT(closestApproach(*raycaster, trajectory), clearance)
          << name << " kind " << static_cast<int>(kind);
    }
  }
}

// The town's second route: one lap re-enters its block loop twice, each time driving a
// stretch it drove before in the same direction (what a loop closure needs), and otherwise
// keeps to new streets and clear of the houses. The other scenes have no such route.
TEST(BuiltinScenesTest, TownTwoLoopsRouteClosesTwoLoopsPerLap) {
  const BuiltinScene town = makeTown();
  const StampedTrajectory lap = makeSceneTrajectory(town, TrajectoryKind::kTwoLoops, 10.0);
  ASSERT_GT(lap.size(), 1000u);
  double length = 0.0;
  for (size_t i = 1; i < lap.size(); ++i) {
    length += (lap[i].T_G_C.translation() - lap[i - 1].T_G_C.translation()).norm();
  }
  // 1260 m between the waypoints; the 12 turns of 12 m radius cut 5.2 m each.
  EXPECT_NEAR(length, 1260.0 - 12 * (24.0 - 6.0 * M_PI), 3.0);

  // Revisit: a pose within 1.5 m of one at least 30 s earlier, looking the same way (15 deg).
  const auto forward = [](const StampedPose& p) -> Eigen::Vector3d {
    return p.T_G_C.rotationMatrix().col(2);
  };
  std::vector<bool> revisit(lap.size(), false);
  for (size_t i = 0; i < lap.size(); ++i) {
    for (size_t j = 0; j < i; ++j) {
      if (lap[i].timestamp_s - lap[j].timestamp_s < 30.0) break;
      if ((lap[i].T_G_C.translation() - lap[j].T_G_C.translation()).norm() < 1.5 &&
          forward(lap[i]).dot(forward(lap[j])) > std::cos(15.0 * M_PI / 180.0)) {
        revisit[i] = true;
        break;
      }
    }
  }
  struct Episode {
    size_t first, last;
  };
  std::vector<Episode> episodes;
  for (size_t i = 0; i < lap.size(); ++i) {
    if (!revisit[i]) continue;
    if (!episodes.empty() && episodes.back().last + 1 == i) {
      episodes.back().last = i;
    } else {
      episodes.push_back({i, i});
    }
  }
  ASSERT_EQ(episodes.size(), 2u);
  const auto at = [&](size_t i) { return lap[i].T_G_C.translation().head<2>(); };
  // Closure 1: east along y = 0 from the corner (70, 0), to the next crossing at least.
  EXPECT_LT((at(episodes[0].first) - Eigen::Vector2d(70, 0)).norm(), 20.0);
  EXPECT_GT(at(episodes[0].last).x(), 130.0);
  // Closure 2: west along y = 70 from (140, 70), then south to the lap's end at (70, 0).
  EXPECT_LT((at(episodes[1].first) - Eigen::Vector2d(140, 70)).norm(), 20.0);
  EXPECT_EQ(episodes[1].last, lap.size() - 1);
  // The second closure is wide: 630 m of new streets after the first revisit ends.
  EXPECT_GT(lap[episodes[1].first].timestamp_s - lap[episodes[0].last].timestamp_s,
            590.0 / town.motion.speed_mps);

  std::string error;
  const auto raycaster = TriangleMeshRaycaster::create(town.mesh, &error);
  ASSERT_NE(raycaster, nullptr) << error;
  EXPECT_GT(closestApproach(*raycaster, lap), 0.8);
  expectTownOnly("two-loops", TrajectoryKind::kTwoLoops);
}

// The town's street turn: KITTI's sharp turns at car speed (90 degrees within 40-50 m at
// 10-13 m/s, up to 3 degrees a frame at 10 Hz), eased in and out as a driver does, clear of
// the houses. Only the town has it.
TEST(BuiltinScenesTest, TownStreetTurnIsAKittiLikeCorner) {
  const BuiltinScene town = makeTown();
  const StampedTrajectory drive = makeSceneTrajectory(town, TrajectoryKind::kStreetTurn, 10.0);
  ASSERT_GT(drive.size(), 50u);
  double length = 0.0, max_speed = 0.0, max_turn_deg = 0.0, turn_deg = 0.0;
  double previous_turn = 0.0, max_turn_change_deg = 0.0;  // the yaw rate's steps
  double turn_start = -1.0, turn_end = -1.0;  // path length where the heading turns
  const auto heading = [](const StampedPose& p) {
    const Eigen::Vector3d f = p.T_G_C.rotationMatrix().col(2);
    return std::atan2(f.y(), f.x()) * 180.0 / M_PI;
  };
  for (size_t i = 1; i < drive.size(); ++i) {
    const double step = (drive[i].T_G_C.translation() - drive[i - 1].T_G_C.translation()).norm();
    length += step;
    max_speed = std::max(max_speed, step * 10.0);
    const double turn = std::abs(heading(drive[i]) - heading(drive[i - 1]));
    max_turn_deg = std::max(max_turn_deg, turn);
    max_turn_change_deg = std::max(max_turn_change_deg, std::abs(turn - previous_turn));
    previous_turn = turn;
    turn_deg += turn;
    if (turn > 0.1) {
      if (turn_start < 0.0) turn_start = length - step;
      turn_end = length;
    }
  }
  // 130 m between the waypoints; the 22 m arc cuts 2 * 22 - 22 pi / 2 = 9.4 m.
  EXPECT_NEAR(length, 130.0 - (44.0 - 11.0 * M_PI), 0.5);
  EXPECT_NEAR(max_speed, 11.0, 0.05);
  EXPECT_NEAR(turn_deg, 90.0, 0.5);
  EXPECT_NEAR(max_turn_deg, 11.0 / 22.0 * 0.1 * 180.0 / M_PI, 0.26);  // 2.9, 0.25-degree steps
  EXPECT_LE(max_turn_deg, 3.0 + 0.26);
  // 35 m of arc, eased in and out over 10 m: the yaw rate ramps up over about 9 frames
  // (2.9 / 9 = 0.32 degrees a frame more each frame) instead of jumping.
  EXPECT_NEAR(turn_end - turn_start, 11.0 * M_PI + 10.0, 2.5);
  EXPECT_LT(max_turn_change_deg, 0.45);
  // Drives at car height, level, on the road.
  EXPECT_NEAR(drive.front().T_G_C.translation().z(), 1.6, 1e-9);
  EXPECT_NEAR(drive.back().T_G_C.translation().head<2>().x(), 70.0, 1e-6);

  std::string error;
  const auto raycaster = TriangleMeshRaycaster::create(town.mesh, &error);
  ASSERT_NE(raycaster, nullptr) << error;
  EXPECT_GT(closestApproach(*raycaster, drive), 1.5);
  expectTownOnly("street-turn", TrajectoryKind::kStreetTurn);
}

}  // namespace
}  // namespace cblox
