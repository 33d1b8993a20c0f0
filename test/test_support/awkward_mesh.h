#pragma once

// Test helpers for mesh file round trips: a random mesh full of awkward floats, and a bitwise
// comparison. Test-only; thread-safe (no shared state).

#include <cstdint>
#include <cstring>
#include <limits>
#include <random>

#include <gtest/gtest.h>
#include <Eigen/Core>

#include "core/mesh/mesh.h"

namespace cblox::test {

/// A random mesh (the same for the same arguments) of num_vertices (>= 2) vertices and
/// num_vertices / 2 triangles, with awkward floats on purpose: tiny, huge, negative zero, a
/// denormal, the float extremes, values with no short decimal form. With `colors` every vertex
/// gets a random colour, with `normals` a random unit normal.
inline Mesh awkwardMesh(uint32_t seed, bool colors, bool normals, size_t num_vertices = 200) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> uniform(-10.0f, 10.0f);
  std::uniform_int_distribution<int> byte(0, 255);
  Mesh m;
  for (size_t i = 0; i < num_vertices; ++i) {
    m.vertices.emplace_back(uniform(rng), uniform(rng) * 1e-6f, uniform(rng) * 1e6f);
    if (colors) {
      m.colors.push_back(Color{static_cast<uint8_t>(byte(rng)), static_cast<uint8_t>(byte(rng)),
                               static_cast<uint8_t>(byte(rng))});
    }
    if (normals)
      m.normals.push_back(Eigen::Vector3f(uniform(rng), uniform(rng), uniform(rng)).normalized());
  }
  m.vertices[0] = Eigen::Vector3f(0.1f, -0.0f, std::numeric_limits<float>::denorm_min());
  m.vertices[1] = Eigen::Vector3f(std::numeric_limits<float>::max(),
                                  std::numeric_limits<float>::lowest(), 1.0f / 3.0f);
  std::uniform_int_distribution<int> index(0, static_cast<int>(num_vertices) - 1);
  for (size_t i = 0; i < num_vertices / 2; ++i) {
    m.triangles.emplace_back(index(rng), index(rng), index(rng));
  }
  return m;
}

/// Expects `a` and `b` to have bitwise-equal vertices (so -0.0 and denormals count) and equal
/// colours, normals and triangles.
inline void expectSameMesh(const Mesh& a, const Mesh& b) {
  ASSERT_EQ(a.numVertices(), b.numVertices());
  ASSERT_EQ(a.numTriangles(), b.numTriangles());
  for (size_t i = 0; i < a.numVertices(); ++i) {
    ASSERT_EQ(std::memcmp(a.vertices[i].data(), b.vertices[i].data(), sizeof(float) * 3), 0)
        << "vertex " << i << ": " << a.vertices[i].transpose() << " vs "
        << b.vertices[i].transpose();
  }
  EXPECT_TRUE(a.colors == b.colors);
  EXPECT_TRUE(a.normals == b.normals);
  EXPECT_TRUE(a.triangles == b.triangles);
}

}  // namespace cblox::test
