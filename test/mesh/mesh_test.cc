#include "core/mesh/mesh.h"

#include <cmath>
#include <numbers>

#include <gtest/gtest.h>

namespace cblox {
namespace {

Mesh triangle(float z, bool colors, bool normals) {
  Mesh m;
  m.vertices = {{0, 0, z}, {1, 0, z}, {0, 1, z}};
  if (colors) m.colors = {{1, 2, 3}, {4, 5, 6}, {7, 8, 9}};
  if (normals) m.normals.assign(3, Eigen::Vector3f::UnitZ());
  m.triangles = {{0, 1, 2}};
  return m;
}

TEST(Mesh, EmptyAndCounts) {
  Mesh m;
  EXPECT_TRUE(m.empty());
  m = triangle(0, true, true);
  EXPECT_FALSE(m.empty());
  EXPECT_EQ(m.numVertices(), 3u);
  EXPECT_EQ(m.numTriangles(), 1u);
  EXPECT_EQ(m.validate(), "");
  m.clear();
  EXPECT_TRUE(m.empty());
}

TEST(Mesh, AppendOffsetsIndicesAndKeepsSharedAttributes) {
  Mesh m = triangle(0, true, true);
  m.append(triangle(1, true, true));
  ASSERT_EQ(m.numVertices(), 6u);
  ASSERT_EQ(m.numTriangles(), 2u);
  EXPECT_EQ(m.triangles[1], Eigen::Vector3i(3, 4, 5));
  EXPECT_EQ(m.vertices[3], Eigen::Vector3f(0, 0, 1));
  EXPECT_EQ(m.colors.size(), 6u);
  EXPECT_EQ(m.normals.size(), 6u);
  EXPECT_EQ(m.validate(), "");

  // Appending to an empty mesh copies; appending an empty mesh is a no-op.
  Mesh e;
  e.append(triangle(0, true, false));
  EXPECT_EQ(e.colors.size(), 3u);
  e.append(Mesh{});
  EXPECT_EQ(e.numVertices(), 3u);

  // An attribute missing on one side is dropped.
  e.append(triangle(2, false, true));
  EXPECT_EQ(e.numVertices(), 6u);
  EXPECT_TRUE(e.colors.empty());
  EXPECT_TRUE(e.normals.empty());
  EXPECT_EQ(e.validate(), "");
}

TEST(Mesh, ValidateNamesTheViolation) {
  Mesh m = triangle(0, true, false);
  m.colors.pop_back();
  EXPECT_NE(m.validate().find("colours"), std::string::npos);
  m = triangle(0, false, true);
  m.normals.push_back(Eigen::Vector3f::UnitX());
  EXPECT_NE(m.validate().find("normals"), std::string::npos);
  m = triangle(0, false, false);
  m.triangles.push_back({0, 3, 1});
  EXPECT_NE(m.validate().find("triangle 1"), std::string::npos);
  m.triangles.back() = {0, -1, 1};
  EXPECT_NE(m.validate().find("-1"), std::string::npos);
}

TEST(Mesh, TransformMovesVerticesAndRotatesNormals) {
  const Mesh m_B = triangle(0, true, true);
  // 90 degrees about x, then translate.
  const Transformation T_A_B(Eigen::Quaternionf(Eigen::AngleAxisf(std::numbers::pi_v<float> / 2,
                                                                  Eigen::Vector3f::UnitX())),
                             Eigen::Vector3f(1, 2, 3));
  const Mesh m_A = transformMesh(T_A_B, m_B);
  ASSERT_EQ(m_A.numVertices(), 3u);
  EXPECT_TRUE(m_A.vertices[1].isApprox(Eigen::Vector3f(2, 2, 3), 1e-6f));
  EXPECT_TRUE(m_A.vertices[2].isApprox(Eigen::Vector3f(1, 2, 4), 1e-6f));
  for (const auto& n : m_A.normals) {
    EXPECT_LT((n - Eigen::Vector3f(0, -1, 0)).norm(), 1e-6f);  // z rotated about x by +90
  }
  EXPECT_EQ(m_A.colors, m_B.colors);
  EXPECT_EQ(m_A.triangles, m_B.triangles);
  // Round trip.
  const Mesh back = transformMesh(T_A_B.inverse(), m_A);
  for (size_t i = 0; i < 3; ++i) EXPECT_LT((back.vertices[i] - m_B.vertices[i]).norm(), 1e-6f);
}

}  // namespace
}  // namespace cblox
