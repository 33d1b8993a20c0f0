#include "core/eval/mesh_height.h"

#include <stdexcept>
#include <vector>

#include <gtest/gtest.h>

namespace cblox {
namespace {

TEST(MeshHeightTest, ParsesTheSixAxes) {
  EXPECT_EQ(*parseUpAxis("z"), Eigen::Vector3d::UnitZ());
  EXPECT_EQ(*parseUpAxis("-y"), -Eigen::Vector3d::UnitY());
  EXPECT_EQ(*parseUpAxis("x"), Eigen::Vector3d::UnitX());
  for (const char* bad : {"", "-", "up", "+z", "zz", "--y", "Y"}) {
    EXPECT_FALSE(parseUpAxis(bad).has_value()) << bad;
  }
}

TEST(MeshHeightTest, TurnsEachAxisUpKeepingAFrame) {
  // A vertex on the up axis goes to +z; a right-handed frame stays right-handed.
  for (const char* name : {"x", "y", "z", "-x", "-y", "-z"}) {
    SCOPED_TRACE(name);
    const Eigen::Vector3d up = *parseUpAxis(name);
    Mesh mesh;
    mesh.vertices = {up.cast<float>(), Eigen::Vector3f(1, 2, 3)};
    mesh.normals = {up.cast<float>(), Eigen::Vector3f::UnitX()};
    mesh.triangles = {Eigen::Vector3i(0, 1, 1)};
    const Mesh turned = turnedUp(mesh, up);
    EXPECT_EQ(turned.vertices[0], Eigen::Vector3f::UnitZ());
    EXPECT_EQ(turned.normals[0], Eigen::Vector3f::UnitZ());
    EXPECT_FLOAT_EQ(turned.vertices[1].norm(), Eigen::Vector3f(1, 2, 3).norm());
    EXPECT_EQ(turned.triangles, mesh.triangles);
    // The height along `up` before is z after.
    EXPECT_FLOAT_EQ(turned.vertices[1].z(), up.cast<float>().dot(Eigen::Vector3f(1, 2, 3)));
  }
  // A camera frame (x right, y down, z ahead) turned -y up: x right, y ahead, z up.
  Mesh camera;
  camera.vertices = {Eigen::Vector3f(1, -2, 5)};  // 1 right, 2 up, 5 ahead
  const Mesh turned = turnedUp(camera, -Eigen::Vector3d::UnitY());
  EXPECT_EQ(turned.vertices[0], Eigen::Vector3f(1, 5, 2));
  EXPECT_THROW(turnedUp(camera, Eigen::Vector3d(1, 1, 0).normalized()), std::invalid_argument);
}

TEST(MeshHeightTest, HeightsAboveTheLowestVertex) {
  Mesh mesh;
  mesh.vertices = {{0, 3, 1}, {0, -1, 2}, {5, 0.5, 0}};
  const std::vector<double> z = vertexHeights(mesh, Eigen::Vector3d::UnitZ());
  EXPECT_EQ(z, (std::vector<double>{1.0, 2.0, 0.0}));
  const std::vector<double> down_y = vertexHeights(mesh, -Eigen::Vector3d::UnitY());
  EXPECT_EQ(down_y, (std::vector<double>{0.0, 4.0, 2.5}));
  EXPECT_TRUE(vertexHeights(Mesh{}, Eigen::Vector3d::UnitZ()).empty());
}

}  // namespace
}  // namespace cblox
