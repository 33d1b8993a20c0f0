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
      double closest = 1e9;
      for (const StampedPose& pose : trajectory) {
        closest = std::min(closest, raycaster->closestPoint(pose.T_G_C.translation()).distance);
      }
      EXPECT_GT(closest, clearance) << name << " kind " << static_cast<int>(kind);
    }
  }
}

}  // namespace
}  // namespace cblox
