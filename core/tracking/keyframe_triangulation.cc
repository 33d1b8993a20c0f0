#include "core/tracking/keyframe_triangulation.h"

#include <algorithm>
#include <cmath>
#include <mutex>
#include <shared_mutex>
#include <sstream>

#include <Eigen/SVD>

#include "core/tracking/common_nodes.h"
#include "core/tracking/feature_matcher.h"
#include "core/tracking/landmark.h"

namespace cblox {

std::string KeyframeTriangulationConfig::validate() const {
  std::ostringstream error;
  if (neighbours < 0) {
    error << "neighbours must be >= 0, got " << neighbours;
  } else if (!(epipole_radius_factor >= 0.0 && std::isfinite(epipole_radius_factor))) {
    error << "epipole_radius_factor must be finite and >= 0, got " << epipole_radius_factor;
  } else if (!(epipolar_chi2 > 0.0 && std::isfinite(epipolar_chi2))) {
    error << "epipolar_chi2 must be finite and > 0, got " << epipolar_chi2;
  } else if (!(max_mono_parallax_cos > -1.0 && max_mono_parallax_cos <= 1.0)) {
    error << "max_mono_parallax_cos must be in (-1, 1], got " << max_mono_parallax_cos;
  } else if (!(chi2_mono > 0.0 && std::isfinite(chi2_mono))) {
    error << "chi2_mono must be finite and > 0, got " << chi2_mono;
  } else if (!(chi2_stereo > 0.0 && std::isfinite(chi2_stereo))) {
    error << "chi2_stereo must be finite and > 0, got " << chi2_stereo;
  } else if (!(scale_ratio_factor >= 1.0 && std::isfinite(scale_ratio_factor))) {
    error << "scale_ratio_factor must be finite and >= 1, got " << scale_ratio_factor;
  }
  return error.str();
}

namespace {

double square(double x) { return x * x; }

// A measured right coordinate and depth (stereo or RGB-D): the third residual applies.
bool hasStereo(const FrameFeatures& f, size_t i) { return f.right_u[i] >= 0.0f && f.hasDepth(i); }

Eigen::Vector2d normalisedCoordinates(const FrameFeatures& f, size_t i,
                                      const PinholeIntrinsics& k) {
  return {(f.keypoints[i].u - k.cx) / k.fx, (f.keypoints[i].v - k.cy) / k.fy};
}

// Cosine of the angle the stereo baseline subtends at the feature's depth (ORB-SLAM2's
// cosParallaxStereo); 2 (above any cosine) without stereo.
double stereoParallaxCos(const FrameFeatures& f, size_t i, double baseline_m) {
  if (!hasStereo(f, i)) return 2.0;
  return std::cos(2.0 * std::atan2(0.5 * baseline_m, static_cast<double>(f.depth[i])));
}

// The point is in front of the camera and reprojects onto feature i within the chi2 bound.
bool reprojectsOnto(const FrameFeatures& f, size_t i, const Transformationd& T_C_G,
                    const Eigen::Vector3d& p_G, const TrackingCamera& camera,
                    const ScalePyramid& pyramid, const KeyframeTriangulationConfig& config) {
  const Eigen::Vector3d p_C = T_C_G * p_G;
  if (!(p_C.z() > 0.0)) return false;
  const PinholeIntrinsics& k = camera.intrinsics;
  const double inv_z = 1.0 / p_C.z();
  const double u = k.fx * p_C.x() * inv_z + k.cx;
  const double v = k.fy * p_C.y() * inv_z + k.cy;
  const Keypoint& kp = f.keypoints[i];
  double e2 = square(u - kp.u) + square(v - kp.v);
  double chi2 = config.chi2_mono;
  if (hasStereo(f, i)) {
    e2 += square(u - camera.bf() * inv_z - f.right_u[i]);
    chi2 = config.chi2_stereo;
  }
  return e2 <= chi2 * pyramid.sigma2(kp.octave);
}

}  // namespace

Eigen::Matrix3d fundamentalMatrix(const Transformationd& T_A_G, const Transformationd& T_B_G,
                                  const PinholeIntrinsics& intrinsics) {
  const Transformationd T_A_B = T_A_G * T_B_G.inverse();
  Eigen::Matrix3d K_inv;
  K_inv << 1.0 / intrinsics.fx, 0.0, -intrinsics.cx / intrinsics.fx,  //
      0.0, 1.0 / intrinsics.fy, -intrinsics.cy / intrinsics.fy,       //
      0.0, 0.0, 1.0;
  return K_inv.transpose() * skew(T_A_B.translation()) * T_A_B.rotationMatrix() * K_inv;
}

std::optional<Eigen::Vector3d> triangulateLinear(const Eigen::Vector2d& xn_a,
                                                 const Eigen::Vector2d& xn_b,
                                                 const Transformationd& T_A_G,
                                                 const Transformationd& T_B_G) {
  const Eigen::Matrix4d P_a = T_A_G.matrix();
  const Eigen::Matrix4d P_b = T_B_G.matrix();
  Eigen::Matrix4d A;
  A.row(0) = xn_a.x() * P_a.row(2) - P_a.row(0);
  A.row(1) = xn_a.y() * P_a.row(2) - P_a.row(1);
  A.row(2) = xn_b.x() * P_b.row(2) - P_b.row(0);
  A.row(3) = xn_b.y() * P_b.row(2) - P_b.row(1);
  const Eigen::JacobiSVD<Eigen::Matrix4d> svd(A, Eigen::ComputeFullV);
  const Eigen::Vector4d x = svd.matrixV().col(3);
  if (!(x.w() != 0.0)) return std::nullopt;
  const Eigen::Vector3d p_G = x.head<3>() / x.w();
  if (!p_G.allFinite()) return std::nullopt;
  return p_G;
}

int searchForTriangulation(const Keyframe& a, const Keyframe& b, const TrackingCamera& camera,
                           const ScalePyramid& pyramid, const KeyframeTriangulationConfig& config,
                           std::vector<std::pair<uint32_t, uint32_t>>* matches) {
  matches->clear();
  const FrameFeatures& fa = a.features();
  const FrameFeatures& fb = b.features();
  const PinholeIntrinsics& k = camera.intrinsics;
  const Eigen::Matrix3d F_ab = fundamentalMatrix(a.T_C_G(), b.T_C_G(), k);
  // The epipole in b: a's camera centre projected (none when it lies in b's focal plane).
  const Eigen::Vector3d centre_a_in_b = b.T_C_G() * a.T_G_C().translation();
  const bool has_epipole = centre_a_in_b.z() != 0.0;
  const double epipole_u = has_epipole ? k.fx * centre_a_in_b.x() / centre_a_in_b.z() + k.cx : 0.0;
  const double epipole_v = has_epipole ? k.fy * centre_a_in_b.y() / centre_a_in_b.z() + k.cy : 0.0;
  const double epipole_r2 = square(config.epipole_radius_factor);

  std::vector<uint8_t> taken(fb.size(), 0);
  std::vector<std::pair<uint32_t, uint32_t>> found;
  std::vector<float> rotations;
  forCommonNodes(
      fa.feature_vector, fb.feature_vector,
      [&](const std::vector<uint32_t>& a_indices, const std::vector<uint32_t>& b_indices) {
        for (const uint32_t i : a_indices) {
          if (a.landmark(i) != nullptr) continue;
          const Keypoint& kp_a = fa.keypoints[i];
          const Eigen::Vector3d line = F_ab.transpose() * Eigen::Vector3d(kp_a.u, kp_a.v, 1.0);
          const double line_norm2 = square(line.x()) + square(line.y());
          if (!(line_norm2 > 0.0)) continue;
          const bool stereo_a = hasStereo(fa, i);
          int best_distance = kOrbDistanceLow + 1;
          int best = -1;
          for (const uint32_t j : b_indices) {
            if (taken[j] || b.landmark(j) != nullptr) continue;
            const int d = hammingDistance(fa.descriptors[i], fb.descriptors[j]);
            if (d >= best_distance) continue;
            const Keypoint& kp_b = fb.keypoints[j];
            if (has_epipole && !stereo_a && !hasStereo(fb, j) &&
                square(epipole_u - kp_b.u) + square(epipole_v - kp_b.v) <
                    epipole_r2 * pyramid.scale(kp_b.octave)) {
              continue;  // too close to the epipole: little parallax
            }
            const double residual = line.dot(Eigen::Vector3d(kp_b.u, kp_b.v, 1.0));
            if (square(residual) / line_norm2 >=
                config.epipolar_chi2 * pyramid.sigma2(kp_b.octave)) {
              continue;
            }
            best_distance = d;
            best = static_cast<int>(j);
          }
          if (best < 0) continue;
          const uint32_t j = static_cast<uint32_t>(best);
          taken[j] = 1;
          found.emplace_back(i, j);
          rotations.push_back(kp_a.angle_deg - fb.keypoints[j].angle_deg);
        }
      });
  if (config.check_orientation) {
    for (const size_t m : consistentRotations(rotations)) matches->push_back(found[m]);
  } else {
    *matches = std::move(found);
  }
  std::sort(matches->begin(), matches->end());
  return static_cast<int>(matches->size());
}

std::optional<Eigen::Vector3d> triangulateMatch(
    const FrameFeatures& a, const Transformationd& T_A_G, uint32_t index_a, const FrameFeatures& b,
    const Transformationd& T_B_G, uint32_t index_b, const TrackingCamera& camera,
    const ScalePyramid& pyramid, const KeyframeTriangulationConfig& config) {
  const PinholeIntrinsics& k = camera.intrinsics;
  const Eigen::Vector2d xn_a = normalisedCoordinates(a, index_a, k);
  const Eigen::Vector2d xn_b = normalisedCoordinates(b, index_b, k);
  const Transformationd T_G_A = T_A_G.inverse();
  const Transformationd T_G_B = T_B_G.inverse();
  const Eigen::Vector3d ray_a = T_G_A.rotation() * xn_a.homogeneous();
  const Eigen::Vector3d ray_b = T_G_B.rotation() * xn_b.homogeneous();
  const double cos_rays = ray_a.dot(ray_b) / (ray_a.norm() * ray_b.norm());
  const bool stereo_a = hasStereo(a, index_a);
  const bool stereo_b = hasStereo(b, index_b);
  const double cos_stereo_a = stereoParallaxCos(a, index_a, camera.baseline_m);
  const double cos_stereo_b = stereoParallaxCos(b, index_b, camera.baseline_m);

  std::optional<Eigen::Vector3d> p_G;
  if (cos_rays < std::min(cos_stereo_a, cos_stereo_b) && cos_rays > 0.0 &&
      (stereo_a || stereo_b || cos_rays < config.max_mono_parallax_cos)) {
    p_G = triangulateLinear(xn_a, xn_b, T_A_G, T_B_G);
  } else if (stereo_a && cos_stereo_a <= cos_stereo_b) {
    p_G = T_G_A * a.unproject(index_a, camera);
  } else if (stereo_b && cos_stereo_b < cos_stereo_a) {
    p_G = T_G_B * b.unproject(index_b, camera);
  }
  if (!p_G) return std::nullopt;  // no stereo and too little parallax (or at infinity)

  if (!reprojectsOnto(a, index_a, T_A_G, *p_G, camera, pyramid, config) ||
      !reprojectsOnto(b, index_b, T_B_G, *p_G, camera, pyramid, config)) {
    return std::nullopt;
  }
  // Scale consistency: the distances must agree with the levels the features were found at.
  const double distance_a = (*p_G - T_G_A.translation()).norm();
  const double distance_b = (*p_G - T_G_B.translation()).norm();
  if (!(distance_a > 0.0 && distance_b > 0.0)) return std::nullopt;
  const double ratio_distance = distance_b / distance_a;
  const double ratio_octave = static_cast<double>(pyramid.scale(a.keypoints[index_a].octave)) /
                              pyramid.scale(b.keypoints[index_b].octave);
  const double factor = config.scale_ratio_factor * pyramid.scaleFactor();
  if (ratio_distance * factor < ratio_octave || ratio_distance > ratio_octave * factor) {
    return std::nullopt;
  }
  return p_G;
}

std::vector<TriangulatedMatch> triangulateNewPoints(const Keyframe& a, const Keyframe& b,
                                                    const TrackingCamera& camera,
                                                    const ScalePyramid& pyramid,
                                                    const KeyframeTriangulationConfig& config) {
  std::vector<TriangulatedMatch> points;
  const double baseline = (a.T_G_C().translation() - b.T_G_C().translation()).norm();
  if (baseline < camera.baseline_m) return points;
  std::vector<std::pair<uint32_t, uint32_t>> matches;
  searchForTriangulation(a, b, camera, pyramid, config, &matches);
  for (const auto& [i, j] : matches) {
    if (const auto p_G = triangulateMatch(a.features(), a.T_C_G(), i, b.features(), b.T_C_G(), j,
                                          camera, pyramid, config)) {
      points.push_back(TriangulatedMatch{i, j, *p_G});
    }
  }
  return points;
}

std::vector<std::shared_ptr<Landmark>> addTriangulatedLandmarks(
    SparseMap* map, Keyframe* a, Keyframe* b, const std::vector<TriangulatedMatch>& points,
    const ScalePyramid& pyramid) {
  std::vector<std::shared_ptr<Landmark>> created;
  if (a->bad() || b->bad()) return created;
  for (const TriangulatedMatch& m : points) {
    if (a->landmark(m.index_a) != nullptr || b->landmark(m.index_b) != nullptr) continue;
    std::shared_ptr<Landmark> landmark = map->addLandmark(m.p_G, a);
    SparseMap::addObservation(a, m.index_a, landmark.get());
    SparseMap::addObservation(b, m.index_b, landmark.get());
    landmark->updateDescriptor();
    landmark->updateNormalAndDepth(pyramid);
    created.push_back(std::move(landmark));
  }
  return created;
}

std::vector<std::shared_ptr<Landmark>> createNewLandmarks(SparseMap* map, Keyframe* keyframe,
                                                          const TrackingCamera& camera,
                                                          const ScalePyramid& pyramid,
                                                          const KeyframeTriangulationConfig& config,
                                                          const std::function<bool()>& stop_early) {
  std::vector<std::shared_ptr<Landmark>> created;
  std::vector<Keyframe*> neighbours;
  {
    std::shared_lock<std::shared_mutex> lock(map->mutex());
    if (keyframe->bad()) return created;
    neighbours = keyframe->bestCovisible(static_cast<size_t>(config.neighbours));
  }
  for (size_t n = 0; n < neighbours.size(); ++n) {
    if (n > 0 && stop_early && stop_early()) break;
    Keyframe* neighbour = neighbours[n];
    std::vector<TriangulatedMatch> points;
    int change_index = 0;
    {
      std::shared_lock<std::shared_mutex> lock(map->mutex());
      if (keyframe->bad() || neighbour->bad()) continue;
      change_index = map->changeIndex();
      points = triangulateNewPoints(*keyframe, *neighbour, camera, pyramid, config);
    }
    if (points.empty()) continue;
    std::unique_lock<std::shared_mutex> lock(map->mutex());
    if (map->changeIndex() != change_index) continue;  // poses moved: the points are stale
    std::vector<std::shared_ptr<Landmark>> added =
        addTriangulatedLandmarks(map, keyframe, neighbour, points, pyramid);
    created.insert(created.end(), std::make_move_iterator(added.begin()),
                   std::make_move_iterator(added.end()));
  }
  return created;
}

}  // namespace cblox
