#include "core/integrator/ray_point_screen.h"

#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include "core/geometry/cpu_features.h"
#include "core/tsdf/block_index.h"

namespace cblox {
namespace {

struct Screened {
  std::vector<ScreenedPoint> accepted;
  IntegrationStats stats;
};

Screened screenAll(const RayPointScreen& screen, const std::vector<Eigen::Vector3f>& points,
                   uint32_t first_index) {
  Screened out;
  out.accepted.resize(points.size());
  out.accepted.resize(
      screen.screen(points.data(), first_index, points.size(), out.accepted.data(), &out.stats));
  return out;
}

// Identity rotation, sensor at (1, 2, 3), 0.1 m cells, ray lengths in [0.5, 4] m, grid
// bound 100 m.
RayPointScreen::Frame analyticFrame() {
  return {
      Eigen::Matrix3f::Identity(), Eigen::Vector3f(1.0f, 2.0f, 3.0f), 0.25f, 16.0f, 100.0f, 10.0f};
}

// Thirteen points (one AVX2 group of eight and a tail of five), each of a known fate.
std::vector<Eigen::Vector3f> analyticPoints() {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float inf = std::numeric_limits<float>::infinity();
  return {
      {0.25f, -0.05f, 1.0f},   // 0: accepted, p_G (1.25, 1.95, 4.0): cell (12, 19, 40)
      {nan, 0.0f, 1.0f},       // 1: invalid
      {0.0f, 0.0f, 0.4f},      // 2: out of range (0.16 < 0.25)
      {0.0f, 0.0f, 0.5f},      // 3: accepted at exactly the minimum length: cell (10, 20, 35)
      {0.0f, inf, 1.0f},       // 4: invalid
      {0.0f, 0.0f, 4.0f},      // 5: accepted at exactly the maximum length: cell (10, 20, 70)
      {0.0f, 0.0f, 4.01f},     // 6: out of range
      {-2.0f, -2.5f, -1.0f},   // 7: accepted, p_G (-1, -0.5, 2): cell (-10, -5, 20)
      {1e20f, 0.0f, 0.0f},     // 8: out of range (its squared length overflows to inf)
      {-1.05f, 0.0f, -0.02f},  // 9: accepted, p_G (-0.05, 2, 2.98): cell (-1, 20, 29)
      {0.0f, 0.0f, -nan},      // 10: invalid
      {0.0f, 0.0f, 0.1f},      // 11: out of range
      {0.0f, 1.5f, 0.0f},      // 12: accepted, p_G (1, 3.5, 3): cell (10, 35, 30)
  };
}

void expectAnalytic(const Screened& s) {
  const std::vector<std::pair<uint32_t, GridIndex>> expected = {
      {100, {12, 19, 40}},  {103, {10, 20, 35}}, {105, {10, 20, 70}},
      {107, {-10, -5, 20}}, {109, {-1, 20, 29}}, {112, {10, 35, 30}}};
  ASSERT_EQ(s.accepted.size(), expected.size());
  for (size_t i = 0; i < expected.size(); ++i) {
    EXPECT_EQ(s.accepted[i].index, expected[i].first) << i;
    EXPECT_EQ(unpackGridIndex(s.accepted[i].cell), expected[i].second) << i;
  }
  EXPECT_EQ(s.stats.points_invalid, 3u);
  EXPECT_EQ(s.stats.points_out_of_range, 4u);
}

TEST(RayPointScreen, KnownPointsOnePointAtATime) {
  const RayPointScreen screen(analyticFrame(), /*vectorized=*/false);
  ASSERT_FALSE(screen.vectorized());
  expectAnalytic(screenAll(screen, analyticPoints(), 100));
}

TEST(RayPointScreen, KnownPointsOnAvx2) {
  if (!cpuHasAvx2()) GTEST_SKIP() << "this CPU has no AVX2";
  const RayPointScreen screen(analyticFrame(), /*vectorized=*/true);
  ASSERT_TRUE(screen.vectorized());
  expectAnalytic(screenAll(screen, analyticPoints(), 100));
}

TEST(RayPointScreen, PointsBeyondTheGridAndASensorBeyondItAreInvalid) {
  for (const bool vectorized : {false, true}) {
    if (vectorized && !cpuHasAvx2()) continue;
    RayPointScreen::Frame frame = analyticFrame();
    frame.max_length_squared = 1e6f;
    // p_G x = 1 + 98.9 < 100 is accepted, 1 + 99 = 100 is not (the bound is strict).
    const std::vector<Eigen::Vector3f> points(9, Eigen::Vector3f(99.0f, 0.0f, 0.0f));
    std::vector<Eigen::Vector3f> near_edge = points;
    near_edge[8] = Eigen::Vector3f(98.9f, 0.0f, 0.0f);
    Screened s = screenAll(RayPointScreen(frame, vectorized), near_edge, 0);
    ASSERT_EQ(s.accepted.size(), 1u) << vectorized;
    EXPECT_EQ(s.accepted[0].index, 8u);
    EXPECT_EQ(s.stats.points_invalid, 8u);
    // A sensor outside the bound rejects every point.
    RayPointScreen::Frame far_sensor = analyticFrame();
    far_sensor.t_G_C = Eigen::Vector3f(0.0f, -100.0f, 0.0f);
    s = screenAll(RayPointScreen(far_sensor, vectorized), analyticPoints(), 0);
    EXPECT_TRUE(s.accepted.empty());
    EXPECT_EQ(s.stats.points_invalid, 9u);  // 3 not finite, 6 in range but off the grid
    EXPECT_EQ(s.stats.points_out_of_range, 4u);
  }
}

// Random clouds under random poses, with non-finite, out-of-range and near-boundary points
// mixed in: the AVX2 screen gives exactly the portable one's output, for every run length.
TEST(RayPointScreen, Avx2EqualsOnePointAtATimeOnRandomClouds) {
  if (!cpuHasAvx2()) GTEST_SKIP() << "this CPU has no AVX2";
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> coordinate(-6.0f, 6.0f);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  size_t total_accepted = 0, total_invalid = 0, total_out = 0;
  for (int trial = 0; trial < 200; ++trial) {
    RayPointScreen::Frame frame;
    frame.R_G_C =
        Eigen::Quaternionf(unit(rng) - 0.5f, unit(rng) - 0.5f, unit(rng) - 0.5f, unit(rng) - 0.5f)
            .normalized()
            .toRotationMatrix();
    frame.t_G_C = Eigen::Vector3f(coordinate(rng), coordinate(rng), coordinate(rng)) * 3.0f;
    frame.min_length_squared = 0.01f;
    frame.max_length_squared = 25.0f;
    frame.coordinate_limit = 18.0f;
    frame.cell_size_inv = trial % 2 == 0 ? 50.0f : 25.0f;
    std::vector<Eigen::Vector3f> points(static_cast<size_t>(trial % 70));
    for (Eigen::Vector3f& p : points) {
      p = Eigen::Vector3f(coordinate(rng), coordinate(rng), coordinate(rng));
      const float u = unit(rng);
      if (u < 0.03f) p.x() = std::numeric_limits<float>::quiet_NaN();
      if (u > 0.97f) p.z() = -std::numeric_limits<float>::infinity();
      if (u > 0.5f && u < 0.52f) p = p.normalized() * 5.0f;  // at the maximum length
    }
    const uint32_t first = static_cast<uint32_t>(trial) * 1000u;
    const Screened portable = screenAll(RayPointScreen(frame, false), points, first);
    const Screened avx2 = screenAll(RayPointScreen(frame, true), points, first);
    ASSERT_EQ(avx2.accepted.size(), portable.accepted.size()) << trial;
    for (size_t i = 0; i < portable.accepted.size(); ++i) {
      EXPECT_EQ(avx2.accepted[i].index, portable.accepted[i].index) << trial << " " << i;
      EXPECT_EQ(avx2.accepted[i].cell, portable.accepted[i].cell) << trial << " " << i;
    }
    EXPECT_EQ(avx2.stats.points_invalid, portable.stats.points_invalid) << trial;
    EXPECT_EQ(avx2.stats.points_out_of_range, portable.stats.points_out_of_range) << trial;
    EXPECT_EQ(portable.accepted.size() + portable.stats.points_invalid +
                  portable.stats.points_out_of_range,
              points.size());
    total_accepted += portable.accepted.size();
    total_invalid += portable.stats.points_invalid;
    total_out += portable.stats.points_out_of_range;
  }
  // Every fate occurs often, so the comparison covers them all.
  EXPECT_GT(total_accepted, 1000u);
  EXPECT_GT(total_invalid, 500u);
  EXPECT_GT(total_out, 1000u);
}

}  // namespace
}  // namespace cblox
