// New landmarks triangulated between keyframes (ORB-SLAM2's CreateNewMapPoints): the DLT,
// the fundamental matrix and the matching rules on analytic cases, then two keyframes of the
// simulated hall whose new points are checked against the exact depth images.

#include "core/tracking/keyframe_triangulation.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <mutex>
#include <random>
#include <set>
#include <shared_mutex>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "core/io/tum_trajectory.h"
#include "core/raycast/triangle_mesh_raycaster.h"
#include "core/tracking/feature_matcher.h"
#include "core/tracking/frame_builder.h"
#include "drivers/open_frame_source.h"

namespace cblox {
namespace {

// ---------------------------------------------------------------------------------------
// Analytic cases: a 640 x 480 camera of focal length 400 px, 8 levels of scale 1.2.

TrackingCamera analyticCamera() {
  PinholeIntrinsics k;
  k.fx = k.fy = 400.0;
  k.cx = 320.0;
  k.cy = 240.0;
  k.width = 640;
  k.height = 480;
  return makeTrackingCamera(k, 0.1);
}

Transformationd pose(const Eigen::Vector3d& axis_angle, const Eigen::Vector3d& t) {
  Eigen::Matrix<double, 6, 1> xi;
  xi << t, axis_angle;
  return Transformationd::exp(xi);
}

Eigen::Vector2d project(const TrackingCamera& camera, const Transformationd& T_C_G,
                        const Eigen::Vector3d& p_G) {
  const Eigen::Vector3d p = T_C_G * p_G;
  const PinholeIntrinsics& k = camera.intrinsics;
  return {k.fx * p.x() / p.z() + k.cx, k.fy * p.y() / p.z() + k.cy};
}

OrbDescriptor randomDescriptor(std::mt19937_64* rng) {
  OrbDescriptor d;
  for (auto& w : d.words) w = (*rng)();
  return d;
}

// The descriptor with its first n bits flipped (Hamming distance n).
OrbDescriptor flipped(OrbDescriptor d, int n) {
  for (int b = 0; b < n; ++b) d.setBit(b, !d.bit(b));
  return d;
}

// Hand-built features; every feature in one vocabulary node.
struct FeatureList {
  std::vector<Keypoint> keypoints;
  std::vector<OrbDescriptor> descriptors;
  std::vector<float> right_u, depth;

  uint32_t add(const Eigen::Vector2d& uv, const OrbDescriptor& d, int octave = 0,
               float right = -1.0f, float z = -1.0f) {
    Keypoint k;
    k.u = static_cast<float>(uv.x());
    k.v = static_cast<float>(uv.y());
    k.octave = octave;
    keypoints.push_back(k);
    descriptors.push_back(d);
    right_u.push_back(right);
    depth.push_back(z);
    return static_cast<uint32_t>(keypoints.size() - 1);
  }
  // A feature at the projection of p_G, with stereo when `stereo`.
  uint32_t addPoint(const TrackingCamera& camera, const Transformationd& T_C_G,
                    const Eigen::Vector3d& p_G, const OrbDescriptor& d, bool stereo,
                    int octave = 0) {
    const Eigen::Vector2d uv = project(camera, T_C_G, p_G);
    const double z = (T_C_G * p_G).z();
    return add(uv, d, octave, stereo ? static_cast<float>(uv.x() - camera.bf() / z) : -1.0f,
               stereo ? static_cast<float>(z) : -1.0f);
  }
  std::shared_ptr<FrameFeatures> build() const {
    auto f = std::make_shared<FrameFeatures>();
    f->keypoints = keypoints;
    f->descriptors = descriptors;
    f->right_u = right_u;
    f->depth = depth;
    std::vector<uint32_t> all(keypoints.size());
    for (size_t i = 0; i < all.size(); ++i) all[i] = static_cast<uint32_t>(i);
    f->feature_vector = {{7, all}};
    return f;
  }
};

KeyframeTriangulationConfig noRotationCheck() {
  KeyframeTriangulationConfig config;
  config.check_orientation = false;
  return config;
}

TEST(KeyframeTriangulationTest, ConfigDefaultsAreValidAndBadValuesAreNamed) {
  EXPECT_EQ(KeyframeTriangulationConfig{}.validate(), "");
  KeyframeTriangulationConfig c;
  c.neighbours = -1;
  EXPECT_NE(c.validate().find("neighbours"), std::string::npos);
  c = {};
  c.epipolar_chi2 = 0.0;
  EXPECT_NE(c.validate().find("epipolar_chi2"), std::string::npos);
  c = {};
  c.chi2_stereo = std::nan("");
  EXPECT_NE(c.validate().find("chi2_stereo"), std::string::npos);
  c = {};
  c.scale_ratio_factor = 0.9;
  EXPECT_NE(c.validate().find("scale_ratio_factor"), std::string::npos);
  c = {};
  c.max_mono_parallax_cos = 1.5;
  EXPECT_NE(c.validate().find("max_mono_parallax_cos"), std::string::npos);
}

TEST(KeyframeTriangulationTest, LinearTriangulationRecoversAnExactPoint) {
  const Transformationd T_A_G = pose({0.1, -0.2, 0.05}, {0.3, -0.1, 0.2});
  const Transformationd T_B_G = pose({-0.05, 0.15, 0.1}, {-0.4, 0.2, 0.1});
  const Eigen::Vector3d p_G(1.0, 0.5, 6.0);
  auto normalised = [](const Transformationd& T, const Eigen::Vector3d& p) {
    const Eigen::Vector3d c = T * p;
    return Eigen::Vector2d(c.x() / c.z(), c.y() / c.z());
  };
  const auto p = triangulateLinear(normalised(T_A_G, p_G), normalised(T_B_G, p_G), T_A_G, T_B_G);
  ASSERT_TRUE(p.has_value());
  EXPECT_LT((*p - p_G).norm(), 1e-9);
  // A point behind both cameras is still the ray intersection (the caller rejects it).
  const Eigen::Vector3d q_G(-0.2, 0.3, -4.0);
  const auto q = triangulateLinear(normalised(T_A_G, q_G), normalised(T_B_G, q_G), T_A_G, T_B_G);
  ASSERT_TRUE(q.has_value());
  EXPECT_LT((*q - q_G).norm(), 1e-9);
}

TEST(KeyframeTriangulationTest, FundamentalMatrixHoldsForEveryPointAndItsEpipolarLine) {
  const TrackingCamera camera = analyticCamera();
  const Transformationd T_A_G = pose({0.02, -0.1, 0.03}, {0.1, 0.0, 0.0});
  const Transformationd T_B_G = pose({-0.03, 0.08, -0.02}, {-0.6, 0.05, 0.2});
  const Eigen::Matrix3d F = fundamentalMatrix(T_A_G, T_B_G, camera.intrinsics);
  const Eigen::Vector3d centre_b = T_B_G.inverse().translation();
  const Eigen::Vector2d epipole_a = project(camera, T_A_G, centre_b);
  for (const Eigen::Vector3d& p_G : {Eigen::Vector3d(0.3, 0.2, 5.0), Eigen::Vector3d(-1, 0.5, 9),
                                     Eigen::Vector3d(0.8, -0.6, 3.0)}) {
    const Eigen::Vector3d x_a = project(camera, T_A_G, p_G).homogeneous();
    const Eigen::Vector3d x_b = project(camera, T_B_G, p_G).homogeneous();
    const Eigen::Vector3d line_b = F.transpose() * x_a;
    EXPECT_LT(std::abs(line_b.dot(x_b)) / line_b.head<2>().norm(), 1e-9);  // pixels
    // Every epipolar line of a (F x_b) passes through a's epipole.
    const Eigen::Vector3d line_a = F * x_b;
    EXPECT_LT(std::abs(line_a.dot(epipole_a.homogeneous())) / line_a.head<2>().norm(), 1e-6);
  }
}

// Two keyframes of the analytic camera: a at the origin, b 0.6 m to the right and 0.3 m
// forward, both looking along +z.
struct AnalyticPair {
  TrackingCamera camera = analyticCamera();
  ScalePyramid pyramid{8, 1.2};
  Transformationd T_A_G;
  Transformationd T_B_G = pose({0, 0, 0}, {-0.6, 0.0, -0.3});
  SparseMap map;
  Keyframe* a = nullptr;
  Keyframe* b = nullptr;
  void makeKeyframes(const FeatureList& fa, const FeatureList& fb) {
    std::unique_lock<std::shared_mutex> lock(map.mutex());
    a = map.addKeyframe(0, 0, fa.build(), T_A_G);
    b = map.addKeyframe(1, 1, fb.build(), T_B_G);
  }
  std::vector<std::pair<uint32_t, uint32_t>> search(const KeyframeTriangulationConfig& config) {
    std::shared_lock<std::shared_mutex> lock(map.mutex());
    std::vector<std::pair<uint32_t, uint32_t>> matches;
    const int n = searchForTriangulation(*a, *b, camera, pyramid, config, &matches);
    EXPECT_EQ(n, static_cast<int>(matches.size()));
    return matches;
  }
  // Unit vector perpendicular to the epipolar line in b of a's keypoint at `uv_a`.
  Eigen::Vector2d epipolarNormalInB(const Eigen::Vector2d& uv_a) const {
    const Eigen::Vector3d l =
        fundamentalMatrix(T_A_G, T_B_G, camera.intrinsics).transpose() * uv_a.homogeneous();
    return l.head<2>().normalized();
  }
};

TEST(KeyframeTriangulationTest, MatchesFollowDescriptorsAlongTheEpipolarLineOnly) {
  AnalyticPair s;
  std::mt19937_64 rng(3);
  FeatureList fa, fb;
  const Eigen::Vector3d p0(0.5, 0.2, 6.0), p1(-0.8, -0.3, 8.0), p2(0.1, 0.6, 5.0);
  const OrbDescriptor d0 = randomDescriptor(&rng), d1 = randomDescriptor(&rng),
                      d2 = randomDescriptor(&rng);
  const uint32_t a0 = fa.addPoint(s.camera, s.T_A_G, p0, d0, false);
  const uint32_t a1 = fa.addPoint(s.camera, s.T_A_G, p1, d1, false);
  const uint32_t a2 = fa.addPoint(s.camera, s.T_A_G, p2, d2, false);
  // b: the true features at a descriptor distance of 20; for p0 a decoy of distance 0
  // 2.5 px off the epipolar line (> sqrt(3.84) = 1.96 px at level 0): rejected; for p1 a
  // decoy of distance 0 1.5 px off the line: accepted, it beats the true feature; for p2
  // only a feature of distance 51 (> kOrbDistanceLow = 50): no match.
  const Eigen::Vector2d u0 = project(s.camera, s.T_B_G, p0);
  const Eigen::Vector2d u1 = project(s.camera, s.T_B_G, p1);
  const Eigen::Vector2d n0 = s.epipolarNormalInB(project(s.camera, s.T_A_G, p0));
  const Eigen::Vector2d n1 = s.epipolarNormalInB(project(s.camera, s.T_A_G, p1));
  const uint32_t b0 = fb.add(u0, flipped(d0, 20));
  fb.add(u0 + 2.5 * n0, d0);
  fb.add(u1, flipped(d1, 20));
  const uint32_t b1_decoy = fb.add(u1 + 1.5 * n1, d1);
  fb.add(project(s.camera, s.T_B_G, p2), flipped(d2, kOrbDistanceLow + 1));
  s.makeKeyframes(fa, fb);
  const auto matches = s.search(noRotationCheck());
  const std::vector<std::pair<uint32_t, uint32_t>> expected{{a0, b0}, {a1, b1_decoy}};
  EXPECT_EQ(matches, expected);
  (void)a2;
  // Control: without the epipolar bound the decoy of p0 wins too.
  KeyframeTriangulationConfig loose = noRotationCheck();
  loose.epipolar_chi2 = 1e6;
  const std::vector<std::pair<uint32_t, uint32_t>> expected_loose{{a0, b0 + 1}, {a1, b1_decoy}};
  EXPECT_EQ(s.search(loose), expected_loose);
}

TEST(KeyframeTriangulationTest, MonocularMatchesNearTheEpipoleAreRejected) {
  AnalyticPair s;
  // b straight ahead of a: a's centre projects to b's principal point (an epipole at the
  // centre of the image). p_near projects 8.5 px from it in b (< 10 px at level 0),
  // p_far 11 px (> 10 px); at level 2 the radius is 10 * sqrt(1.44) = 12 px.
  s.T_B_G = pose({0, 0, 0}, {0.0, 0.0, -1.0});
  std::mt19937_64 rng(5);
  auto pointAt = [&](double du, double dv, double z_b) {  // b pixel offset from the epipole
    const Eigen::Vector3d p_B(du / 400.0 * z_b, dv / 400.0 * z_b, z_b);
    return s.T_B_G.inverse() * p_B;
  };
  const Eigen::Vector3d near = pointAt(6.0, 6.0, 4.0);  // 8.49 px
  const Eigen::Vector3d far = pointAt(-11.0, 0.0, 4.0);
  const Eigen::Vector3d far_level2 = pointAt(0.0, 11.0, 4.0);
  FeatureList fa, fb;
  const OrbDescriptor dn = randomDescriptor(&rng), df = randomDescriptor(&rng),
                      d2 = randomDescriptor(&rng), ds = randomDescriptor(&rng);
  fa.addPoint(s.camera, s.T_A_G, near, dn, false);
  const uint32_t a_far = fa.addPoint(s.camera, s.T_A_G, far, df, false);
  fa.addPoint(s.camera, s.T_A_G, far_level2, d2, false, 2);
  const uint32_t a_stereo = fa.addPoint(s.camera, s.T_A_G, near, ds, true);
  fb.addPoint(s.camera, s.T_B_G, near, dn, false);
  const uint32_t b_far = fb.addPoint(s.camera, s.T_B_G, far, df, false);
  fb.addPoint(s.camera, s.T_B_G, far_level2, d2, false, 2);
  const uint32_t b_stereo = fb.addPoint(s.camera, s.T_B_G, near, ds, false);  // a has stereo
  s.makeKeyframes(fa, fb);
  const auto matches = s.search(noRotationCheck());
  const std::vector<std::pair<uint32_t, uint32_t>> expected{{a_far, b_far}, {a_stereo, b_stereo}};
  EXPECT_EQ(matches, expected);
  // Control: without the epipole radius all four match.
  KeyframeTriangulationConfig no_radius = noRotationCheck();
  no_radius.epipole_radius_factor = 0.0;
  EXPECT_EQ(s.search(no_radius).size(), 4u);
}

TEST(KeyframeTriangulationTest, FeaturesWithLandmarksAreSkippedAndEachFeatureOfBMatchesOnce) {
  AnalyticPair s;
  std::mt19937_64 rng(7);
  FeatureList fa, fb;
  // q0 and q1 lie on one ray of b (same pixel in b): both features of a satisfy the
  // epipolar constraint with the single feature of b; the first (lower index) takes it.
  const Eigen::Vector3d ray_b =
      (s.T_B_G.inverse().rotationMatrix() * Eigen::Vector3d(0.1, 0.05, 1));
  const Eigen::Vector3d centre_b = s.T_B_G.inverse().translation();
  const Eigen::Vector3d q0 = centre_b + 5.0 * ray_b, q1 = centre_b + 8.0 * ray_b;
  const OrbDescriptor dq = randomDescriptor(&rng);
  const uint32_t a_q0 = fa.addPoint(s.camera, s.T_A_G, q0, dq, false);
  fa.addPoint(s.camera, s.T_A_G, q1, dq, false);
  const uint32_t b_q = fb.addPoint(s.camera, s.T_B_G, q0, dq, false);
  // r: a landmark on the feature of a; t: a landmark on the feature of b; u: free.
  const Eigen::Vector3d r(0.4, -0.3, 6.0), t(-0.5, 0.4, 7.0), u(0.9, 0.1, 5.0);
  const OrbDescriptor dr = randomDescriptor(&rng), dt = randomDescriptor(&rng),
                      du = randomDescriptor(&rng);
  const uint32_t a_r = fa.addPoint(s.camera, s.T_A_G, r, dr, false);
  fa.addPoint(s.camera, s.T_A_G, t, dt, false);
  const uint32_t a_u = fa.addPoint(s.camera, s.T_A_G, u, du, false);
  fb.addPoint(s.camera, s.T_B_G, r, dr, false);
  const uint32_t b_t = fb.addPoint(s.camera, s.T_B_G, t, dt, false);
  const uint32_t b_u = fb.addPoint(s.camera, s.T_B_G, u, du, false);
  s.makeKeyframes(fa, fb);
  {
    std::unique_lock<std::shared_mutex> lock(s.map.mutex());
    SparseMap::addObservation(s.a, a_r, s.map.addLandmark(r, s.a).get());
    SparseMap::addObservation(s.b, b_t, s.map.addLandmark(t, s.b).get());
  }
  const auto matches = s.search(noRotationCheck());
  const std::vector<std::pair<uint32_t, uint32_t>> expected{{a_q0, b_q}, {a_u, b_u}};
  EXPECT_EQ(matches, expected);
}

TEST(KeyframeTriangulationTest, TriangulatedPointsPassOrFailTheChecksExactly) {
  AnalyticPair s;
  std::mt19937_64 rng(11);
  const Eigen::Vector3d p(0.4, -0.2, 6.0);
  const OrbDescriptor d = randomDescriptor(&rng);
  const KeyframeTriangulationConfig config;
  auto run = [&](const FeatureList& fa, const FeatureList& fb, const Transformationd& T_B_G) {
    return triangulateMatch(*fa.build(), s.T_A_G, 0, *fb.build(), T_B_G, 0, s.camera, s.pyramid,
                            config);
  };
  {  // Mono, wide baseline: the point, up to the float keypoints (1e-5 px at 400 px is
     // 1.5e-7 m at 6 m).
    FeatureList fa, fb;
    fa.addPoint(s.camera, s.T_A_G, p, d, false);
    fb.addPoint(s.camera, s.T_B_G, p, d, false);
    const auto x = run(fa, fb, s.T_B_G);
    ASSERT_TRUE(x.has_value());
    EXPECT_LT((*x - p).norm(), 1e-5);
  }
  {  // Moved 20 px along b's epipolar line: the rays still meet, 2 m further away (the
     // disparity between a and b drops from 40 to 20 px... or rises to 60 px): zero
     // reprojection error without stereo; with a's (true) stereo the right coordinate
     // (disparity 40 px * 0.1 m / 0.6 m = 6.7 px at 6 m) is off by 2.2 or 3.3 px, whose
     // square exceeds 7.8 px^2 at level 0: rejected.
    FeatureList fa, fb, fa_stereo;
    fa.addPoint(s.camera, s.T_A_G, p, d, false);
    fa_stereo.addPoint(s.camera, s.T_A_G, p, d, true);
    const Eigen::Vector2d n = s.epipolarNormalInB(project(s.camera, s.T_A_G, p));
    fb.add(project(s.camera, s.T_B_G, p) + 20.0 * Eigen::Vector2d(-n.y(), n.x()), d);
    const auto moved = run(fa, fb, s.T_B_G);
    ASSERT_TRUE(moved.has_value());
    EXPECT_GT((*moved - p).norm(), 0.1);
    EXPECT_FALSE(run(fa_stereo, fb, s.T_B_G).has_value());
  }
  {  // Scale consistency: dist_b / dist_a is about 1; level 4 in b predicts 1 / 1.2^4 = 0.48,
     // outside [0.48 / 1.8, 0.48 * 1.8]; level 1 predicts 0.83: accepted.
    FeatureList fa, fb4, fb1;
    fa.addPoint(s.camera, s.T_A_G, p, d, false);
    fb4.addPoint(s.camera, s.T_B_G, p, d, false, 4);
    fb1.addPoint(s.camera, s.T_B_G, p, d, false, 1);
    EXPECT_FALSE(run(fa, fb4, s.T_B_G).has_value());
    EXPECT_TRUE(run(fa, fb1, s.T_B_G).has_value());
  }
  {  // 5 cm apart at 6 m: rays within 0.5 degree (cos > 0.9998). Mono: no point. With
     // stereo on b (parallax of its 0.1 m baseline, larger): b's stereo point, exactly.
    const Transformationd T_B_G = pose({0, 0, 0}, {-0.05, 0.0, 0.0});
    FeatureList fa, fb, fb_stereo;
    fa.addPoint(s.camera, s.T_A_G, p, d, false);
    fb.addPoint(s.camera, T_B_G, p, d, false);
    fb_stereo.addPoint(s.camera, T_B_G, p, d, true);
    EXPECT_FALSE(run(fa, fb, T_B_G).has_value());
    const auto x = run(fa, fb_stereo, T_B_G);
    ASSERT_TRUE(x.has_value());
    const Eigen::Vector3d expected = T_B_G.inverse() * fb_stereo.build()->unproject(0, s.camera);
    EXPECT_LT((*x - expected).norm(), 1e-12);
    EXPECT_LT((*x - p).norm(), 1e-5);  // float keypoints and depth
  }
  {  // Rays that meet behind the cameras (a's towards -x, b's, from x = 0.6 m, towards +x;
     // their lines cross at z = -1.3 m) are rejected.
    FeatureList fa, fb;
    fa.add({320.0 - 400.0 * 0.1, 240.0}, d);
    fb.add({320.0 + 400.0 * 0.3, 240.0}, d);
    EXPECT_FALSE(run(fa, fb, s.T_B_G).has_value());
  }
}

TEST(KeyframeTriangulationTest, NewLandmarksComeFromTheBestNeighboursInOrderAndStopEarly) {
  // Keyframe k at the origin, n1 0.6 m to its right, n2 0.6 m to its left. Five free points
  // are seen by k and n1, four by k and n2. 20 landmarks seen by all three (16 of them by n2)
  // make n1 the best covisible keyframe and n2 the second.
  const TrackingCamera camera = analyticCamera();
  const ScalePyramid pyramid(8, 1.2);
  const Transformationd T_K_G;
  const Transformationd T_N1_G = pose({0, 0, 0}, {-0.6, 0, 0});
  const Transformationd T_N2_G = pose({0, 0, 0}, {0.6, 0, 0});
  std::mt19937_64 rng(13);
  FeatureList fk, fn1, fn2;
  std::vector<Eigen::Vector3d> with_n1, with_n2;
  for (int i = 0; i < 5; ++i) with_n1.emplace_back(-0.4 + 0.2 * i, 0.3 - 0.1 * i, 4.0 + 0.5 * i);
  for (int i = 0; i < 4; ++i) with_n2.emplace_back(0.5 - 0.3 * i, -0.2 + 0.15 * i, 6.0 - 0.4 * i);
  for (const Eigen::Vector3d& p : with_n1) {
    const OrbDescriptor d = randomDescriptor(&rng);
    fk.addPoint(camera, T_K_G, p, d, false);
    fn1.addPoint(camera, T_N1_G, p, d, false);
  }
  for (const Eigen::Vector3d& p : with_n2) {
    const OrbDescriptor d = randomDescriptor(&rng);
    fk.addPoint(camera, T_K_G, p, d, false);
    fn2.addPoint(camera, T_N2_G, p, d, false);
  }
  const size_t first_shared_k = fk.keypoints.size(), first_shared_n1 = fn1.keypoints.size(),
               first_shared_n2 = fn2.keypoints.size();
  for (int i = 0; i < 20; ++i) {
    const Eigen::Vector2d uv(20.0 + 25.0 * i, 460.0);  // held features: never matched
    fk.add(uv, randomDescriptor(&rng));
    fn1.add(uv, randomDescriptor(&rng));
    if (i < 16) fn2.add(uv, randomDescriptor(&rng));
  }
  auto build = [&](SparseMap* map) {
    std::unique_lock<std::shared_mutex> lock(map->mutex());
    Keyframe* k = map->addKeyframe(0, 0, fk.build(), T_K_G);
    Keyframe* n1 = map->addKeyframe(1, 1, fn1.build(), T_N1_G);
    Keyframe* n2 = map->addKeyframe(2, 2, fn2.build(), T_N2_G);
    for (int i = 0; i < 20; ++i) {
      Landmark* l = map->addLandmark(Eigen::Vector3d(0, 0, 5), k).get();
      SparseMap::addObservation(k, static_cast<uint32_t>(first_shared_k + i), l);
      SparseMap::addObservation(n1, static_cast<uint32_t>(first_shared_n1 + i), l);
      if (i < 16) SparseMap::addObservation(n2, static_cast<uint32_t>(first_shared_n2 + i), l);
    }
    k->updateConnections();
    EXPECT_EQ(k->bestCovisible(10), (std::vector<Keyframe*>{n1, n2}));
    return std::array<Keyframe*, 3>{k, n1, n2};
  };
  // Which points were made, and with which neighbour; each at its true position.
  auto check = [&](const SparseMap& map, const std::vector<std::shared_ptr<Landmark>>& created,
                   const std::array<Keyframe*, 3>& kf, size_t expected_n1, size_t expected_n2) {
    std::shared_lock<std::shared_mutex> lock(map.mutex());
    size_t n1 = 0, n2 = 0;
    for (const auto& l : created) {
      const int i = l->indexIn(kf[0]);
      ASSERT_GE(i, 0);
      ASSERT_EQ(l->observations().size(), 2u);
      const bool from_n1 = l->indexIn(kf[1]) >= 0;
      const Eigen::Vector3d& truth =
          from_n1 ? with_n1[static_cast<size_t>(i)] : with_n2[static_cast<size_t>(i) - 5];
      EXPECT_LT((l->position() - truth).norm(), 1e-5) << i;
      (from_n1 ? n1 : n2) += 1;
    }
    EXPECT_EQ(n1, expected_n1);
    EXPECT_EQ(n2, expected_n2);
  };
  {
    SparseMap map;
    const auto kf = build(&map);
    check(map, createNewLandmarks(&map, kf[0], camera, pyramid, KeyframeTriangulationConfig{}), kf,
          5, 4);
  }
  {  // A waiting keyframe: asked once, before the second neighbour.
    SparseMap map;
    const auto kf = build(&map);
    int asked = 0;
    const auto created =
        createNewLandmarks(&map, kf[0], camera, pyramid, KeyframeTriangulationConfig{}, [&] {
          ++asked;
          return true;
        });
    EXPECT_EQ(asked, 1);
    check(map, created, kf, 5, 0);
  }
  {  // One neighbour only.
    SparseMap map;
    const auto kf = build(&map);
    KeyframeTriangulationConfig config;
    config.neighbours = 1;
    check(map, createNewLandmarks(&map, kf[0], camera, pyramid, config), kf, 5, 0);
  }
}

// ---------------------------------------------------------------------------------------
// Simulated hall (most surfaces 5-30 m away): two keyframes 0.75 m apart with their exact
// poses and real features (stereo depth, BoW of the default vocabulary). The first keyframe
// holds landmarks on every other stereo feature, matched into the second by BoW (so the two
// are covisible), then CreateNewMapPoints runs on the second. Every new point is compared
// with the exact surface (the scene mesh) along its rays from both camera centres.

struct HallPair {
  TrackingCamera camera;
  CaptureFrame first, second;
  std::shared_ptr<FrameFeatures> f0, f1;
  ScalePyramid pyramid;
};

// Frames `first` and `second` of sim:hall played with `options`.
HallPair renderHallPair(const SourceConfig& options, size_t first, size_t second,
                        const BinaryVocabulary& vocabulary) {
  HallPair h;
  std::string error;
  std::unique_ptr<FrameSource> source = openFrameSource("sim:hall", options, &error);
  EXPECT_NE(source, nullptr) << error;
  if (!source) return h;
  const RectifiedStereoCalibration& calibration = *source->info().stereo;
  h.camera = makeTrackingCamera(calibration.intrinsics, calibration.baseline_m);
  CaptureFrame frame;
  size_t n = 0;
  while (n <= second && source->next(&frame, &error) == FrameSource::Status::kFrame) {
    if (n == first) h.first = frame;
    if (n == second) h.second = frame;
    ++n;
  }
  EXPECT_EQ(n, second + 1) << error;
  if (n != second + 1) return h;
  FrameBuilder builder(h.camera, FrameBuilderConfig{}, &vocabulary);
  h.f0 = builder.fromStereo(h.first.left, h.first.right);
  h.f1 = builder.fromStereo(h.second.left, h.second.right);
  // Keyframes carry BoW vectors (the tracker computes them before making a keyframe).
  builder.index(h.f0.get());
  builder.index(h.f1.get());
  h.pyramid = builder.pyramid();
  return h;
}

// The exact scene surface point (the simulator's mesh) on the ray from centre_G through p_G.
std::optional<Eigen::Vector3d> surfaceOnRay(const TriangleMeshRaycaster& scene,
                                            const Eigen::Vector3d& centre_G,
                                            const Eigen::Vector3d& p_G) {
  const Eigen::Vector3d direction = (p_G - centre_G).normalized();
  Ray r;
  r.origin = centre_G.cast<float>();
  r.direction = direction.cast<float>();
  RaycastHit hit;
  if (!scene.intersect(r, &hit)) return std::nullopt;
  return centre_G + static_cast<double>(hit.t) * direction;
}

// Sorted samples.
struct Samples {
  std::vector<double> v;
  double quantile(double q) const {
    return v[std::min(v.size() - 1, static_cast<size_t>(q * static_cast<double>(v.size())))];
  }
  double fractionAbove(double x) const {
    return static_cast<double>(v.end() - std::upper_bound(v.begin(), v.end(), x)) /
           static_cast<double>(v.size());
  }
};

// Per new landmark, the worse of its two keyframes (X, Y = the other):
//  - depth error: |d - d_true| / d_true of its distance d from X's centre against the
//    surface on that ray (= |z - z_true| / z_true in X);
//  - pixel error: how far, in Y's image, the landmark and that surface point project apart,
//    in pixels of the level of Y's feature: the depth error as a measurement error of the
//    other view, the unit the triangulation's chi2 tests use (near the epipole a large
//    depth error is a small pixel error).
struct HallOutcome {
  size_t landmarks_before = 0, triangulated = 0, far = 0;
  Samples depth_errors, pixel_errors;
  double median_depth = 0.0;
};

// Sets the two keyframes up, runs createNewLandmarks on the second and checks what must hold
// for every new landmark: two observations on features that held none, the landmarks
// already held untouched, the reference keyframe and distance range set.
HallOutcome triangulateHallPair(const HallPair& h) {
  HallOutcome out;
  std::string error;
  const std::shared_ptr<const Mesh> mesh = loadSimSceneMesh("sim:hall", &error);
  EXPECT_NE(mesh, nullptr) << error;
  const std::unique_ptr<TriangleMeshRaycaster> scene =
      mesh ? TriangleMeshRaycaster::create(*mesh, &error) : nullptr;
  EXPECT_NE(scene, nullptr) << error;
  if (!scene || !h.f0 || !h.f1) return out;
  SparseMap map;
  Keyframe* k0 = nullptr;
  Keyframe* k1 = nullptr;
  std::vector<Landmark*> held0, held1;
  {
    std::unique_lock<std::shared_mutex> lock(map.mutex());
    k0 = map.addKeyframe(0, 0, h.f0, h.first.T_G_C->inverse());
    for (size_t i = 0; i < h.f0->size(); i += 2) {
      if (!h.f0->hasDepth(i)) continue;
      auto l = map.addLandmark(*h.first.T_G_C * h.f0->unproject(i, h.camera), k0);
      SparseMap::addObservation(k0, static_cast<uint32_t>(i), l.get());
      l->updateDescriptor();
      l->updateNormalAndDepth(h.pyramid);
    }
    k1 = map.addKeyframe(1, 1, h.f1, h.second.T_G_C->inverse());
    FeatureMatcherConfig matcher;
    matcher.nn_ratio = 0.7f;
    std::vector<Landmark*> matches;
    EXPECT_GT(searchByBow(*k0, *h.f1, matcher, &matches), 15);  // a covisibility edge
    for (size_t j = 0; j < matches.size(); ++j) {
      if (matches[j] != nullptr) {
        SparseMap::addObservation(k1, static_cast<uint32_t>(j), matches[j]);
      }
    }
    k1->updateConnections();
    EXPECT_EQ(k1->bestCovisible(10), std::vector<Keyframe*>{k0});
    held0 = k0->landmarks();
    held1 = k1->landmarks();
  }
  out.landmarks_before = map.numLandmarks();
  const std::vector<std::shared_ptr<Landmark>> created =
      createNewLandmarks(&map, k1, h.camera, h.pyramid, KeyframeTriangulationConfig{});
  out.triangulated = created.size();

  std::shared_lock<std::shared_mutex> lock(map.mutex());
  EXPECT_EQ(map.numLandmarks(), out.landmarks_before + created.size());
  for (size_t i = 0; i < held0.size(); ++i) {
    if (held0[i] != nullptr) {
      EXPECT_EQ(k0->landmark(i), held0[i]) << i;
    }
  }
  for (size_t i = 0; i < held1.size(); ++i) {
    if (held1[i] != nullptr) {
      EXPECT_EQ(k1->landmark(i), held1[i]) << i;
    }
  }
  std::vector<double> depths;
  for (const auto& l : created) {
    EXPECT_EQ(l->observations().size(), 2u);
    const int i0 = l->indexIn(k0), i1 = l->indexIn(k1);
    if (i0 < 0 || i1 < 0) {
      ADD_FAILURE() << "landmark " << l->id << " not observed by both keyframes";
      continue;
    }
    EXPECT_EQ(held0[static_cast<size_t>(i0)], nullptr);
    EXPECT_EQ(held1[static_cast<size_t>(i1)], nullptr);
    EXPECT_EQ(l->referenceKeyframe(), k1);
    EXPECT_GT(l->maxDistance(), 0.0);
    double depth_error = 0.0, pixel_error = 0.0;
    for (const bool first_is_x : {true, false}) {
      const Transformationd& T_G_X = first_is_x ? *h.first.T_G_C : *h.second.T_G_C;
      const Transformationd& T_G_Y = first_is_x ? *h.second.T_G_C : *h.first.T_G_C;
      const Keypoint& kp_y = first_is_x ? h.f1->keypoints[static_cast<size_t>(i1)]
                                        : h.f0->keypoints[static_cast<size_t>(i0)];
      const auto surface = surfaceOnRay(*scene, T_G_X.translation(), l->position());
      if (!surface) {
        ADD_FAILURE() << "landmark " << l->id << " is not in front of any surface";
        return out;
      }
      const double d = (l->position() - T_G_X.translation()).norm();
      const double d_true = (*surface - T_G_X.translation()).norm();
      depth_error = std::max(depth_error, std::abs(d - d_true) / d_true);
      const Transformationd T_Y_G = T_G_Y.inverse();
      pixel_error = std::max(
          pixel_error,
          (project(h.camera, T_Y_G, l->position()) - project(h.camera, T_Y_G, *surface)).norm() /
              h.pyramid.scale(kp_y.octave));
    }
    out.depth_errors.v.push_back(depth_error);
    out.pixel_errors.v.push_back(pixel_error);
    const double z = (h.second.T_G_C->inverse() * l->position()).z();
    depths.push_back(z);
    out.far += z > h.camera.close_depth_m ? 1 : 0;
  }
  std::sort(out.depth_errors.v.begin(), out.depth_errors.v.end());
  std::sort(out.pixel_errors.v.begin(), out.pixel_errors.v.end());
  std::sort(depths.begin(), depths.end());
  if (depths.empty()) return out;
  out.median_depth = depths[depths.size() / 2];
  const Samples& de = out.depth_errors;
  const Samples& pe = out.pixel_errors;
  std::printf(
      "%zu + %zu features, %zu landmarks before, %zu triangulated (%zu beyond %.1f m, median "
      "depth %.1f m); depth error median %.4f p90 %.4f p95 %.4f max %.4f; pixel error (level "
      "pixels) median %.2f p90 %.2f p95 %.2f max %.2f, above 3: %.3f\n",
      h.f0->size(), h.f1->size(), out.landmarks_before, out.triangulated, out.far,
      h.camera.close_depth_m, out.median_depth, de.quantile(0.5), de.quantile(0.9),
      de.quantile(0.95), de.v.back(), pe.quantile(0.5), pe.quantile(0.9), pe.quantile(0.95),
      pe.v.back(), pe.fractionAbove(3.0));
  return out;
}

// The hall tests share the default vocabulary (loaded once).
class KeyframeTriangulationHallTest : public testing::Test {
 protected:
  static void SetUpTestSuite() {
    vocabulary_ = BinaryVocabulary::load(CBLOX_DEFAULT_VOCABULARY, &error_);
  }
  void SetUp() override { ASSERT_TRUE(vocabulary_.has_value()) << error_; }
  static inline std::optional<BinaryVocabulary> vocabulary_;
  static inline std::string error_;
};

TEST_F(KeyframeTriangulationHallTest, LoopKeyframesGainManyFarLandmarks) {
  // At 2 Hz the camera cruises along the hall at 1.5 m/s from frame 3 on, looking ahead:
  // frames 3 and 4 are 0.75 m apart along the viewing direction.
  SourceConfig options;
  options.trajectory = "loop";
  options.sim.rate_hz = 2.0;
  const HallPair h = renderHallPair(options, 3, 4, *vocabulary_);
  ASSERT_TRUE(h.f0 && h.f1);
  const double baseline = (h.first.T_G_C->translation() - h.second.T_G_C->translation()).norm();
  EXPECT_NEAR(baseline, 0.75, 0.01);
  const HallOutcome out = triangulateHallPair(h);
  ASSERT_FALSE(out.depth_errors.v.empty());
  // Measured: 109 new landmarks, 108 of them beyond close_depth_m (landmarks the tracker
  // never makes), median depth 14.5 m.
  EXPECT_GE(out.triangulated, 90u);
  EXPECT_GE(out.far, out.triangulated * 9 / 10);
  // Measured: pixel error median 0.37, p95 1.31 level pixels; one landmark of 109 (0.9 %) is
  // a wrong match 87 px away along the epipolar line (it passes every check; ORB-SLAM2
  // relies on the recent-landmark culling for these).
  EXPECT_LT(out.pixel_errors.quantile(0.5), 0.6);
  EXPECT_LT(out.pixel_errors.quantile(0.95), 2.0);
  EXPECT_LE(out.pixel_errors.fractionAbove(3.0), 0.03);
  // Looking ahead, 0.75 m of forward motion moves a point 15 m away by only a few pixels
  // (none at the epipole), and ORB keypoints are whole pixels of their level: the depth is
  // coarse. Measured: median 4.5 %, p95 19.6 %.
  EXPECT_LT(out.depth_errors.quantile(0.5), 0.07);
}

TEST_F(KeyframeTriangulationHallTest, SidewaysKeyframesTriangulateOnTheTrueSurface) {
  std::string error;
  // The loop's pose at 1.5 s and the same pose 0.75 m to the camera's right (a wide stereo
  // pair), played at 20 Hz from a TUM file.
  SourceConfig loop;
  loop.trajectory = "loop";
  loop.max_frames = 1;
  std::unique_ptr<FrameSource> source = openFrameSource("sim:hall", loop, &error);
  ASSERT_NE(source, nullptr) << error;
  const auto* sim = dynamic_cast<const SimSource*>(source.get());
  ASSERT_NE(sim, nullptr);
  const auto start = interpolatePose(sim->trajectory(), sim->trajectory().front().timestamp_s + 1.5,
                                     std::numeric_limits<double>::infinity());
  ASSERT_TRUE(start.has_value());
  const Transformationd right = pose({0, 0, 0}, {0.75, 0.0, 0.0});
  const std::string path = testing::TempDir() + "/keyframe_triangulation_sideways.txt";
  ASSERT_TRUE(writeTumTrajectory(path, {{0.0, *start}, {0.05, *start * right}}, &error)) << error;
  SourceConfig options;
  options.trajectory = path;
  const HallPair h = renderHallPair(options, 0, 1, *vocabulary_);
  ASSERT_TRUE(h.f0 && h.f1);
  const HallOutcome out = triangulateHallPair(h);
  ASSERT_FALSE(out.depth_errors.v.empty());
  // Measured: 75 new landmarks, 74 beyond close_depth_m.
  EXPECT_GE(out.triangulated, 60u);
  EXPECT_GE(out.far, out.triangulated * 9 / 10);
  // Every landmark lies on the true surface to within what its keypoints can tell: the chi2
  // gate lets a point reproject up to sqrt(5.991) = 2.45 level pixels from its keypoint, and
  // a keypoint is a whole pixel of its level (half a pixel from the true projection).
  // Measured: median 0.35, p95 1.11, max 1.93 level pixels.
  EXPECT_LT(out.pixel_errors.v.back(), 3.0);
  EXPECT_LT(out.pixel_errors.quantile(0.95), 1.5);
  // In depth: 0.75 m sideways at 15 m is a disparity of 23 px (fx = 458), so one pixel is
  // 4 %; points reach 33 m and pyramid level 7 (3.6 px). Measured: median 2.2 %, p95 9.5 %,
  // max 18.4 %.
  EXPECT_LT(out.depth_errors.quantile(0.5), 0.035);
  EXPECT_LT(out.depth_errors.quantile(0.95), 0.13);
  EXPECT_LT(out.depth_errors.v.back(), 0.3);
}

}  // namespace
}  // namespace cblox
