#include "core/tracking/feature_matcher.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "core/tracking/common_nodes.h"

namespace cblox {

namespace {

// Rotation-consistency check: 36 bins of 10 degrees; matches within 30 degrees of the
// dominant change are kept.
constexpr int kRotationBins = 36;
constexpr float kRotationBinDeg = 360.0f / kRotationBins;
constexpr float kRotationToleranceDeg = 30.0f;

// ORB-SLAM2's RadiusByViewingCos: a smaller window when the landmark is seen head on.
float radiusByViewingCos(float view_cos) { return view_cos > 0.998f ? 2.5f : 4.0f; }

struct Best {
  int distance = std::numeric_limits<int>::max();
  int second = std::numeric_limits<int>::max();
  int level = -1, second_level = -1;
  int index = -1;
  void offer(int d, int level_of_candidate, int candidate) {
    if (d < distance) {
      second = distance;
      second_level = level;
      distance = d;
      level = level_of_candidate;
      index = candidate;
    } else if (d < second) {
      second = d;
      second_level = level_of_candidate;
    }
  }
};

// Applies the orientation check to matches (feature index, rotation): unsets the rejected.
template <typename Unset>
int filterByRotation(const std::vector<std::pair<size_t, float>>& matches, Unset unset) {
  std::vector<float> rotations;
  rotations.reserve(matches.size());
  for (const auto& m : matches) rotations.push_back(m.second);
  const std::vector<size_t> keep = consistentRotations(rotations);
  size_t k = 0;
  for (size_t i = 0; i < matches.size(); ++i) {
    if (k < keep.size() && keep[k] == i) {
      ++k;
    } else {
      unset(matches[i].first);
    }
  }
  return static_cast<int>(keep.size());
}

}  // namespace

std::optional<LandmarkProjection> projectLandmark(Landmark* landmark, const Transformationd& T_C_G,
                                                  const TrackingCamera& camera,
                                                  const ScalePyramid& pyramid, float min_view_cos) {
  const Eigen::Vector3d& p_G = landmark->position();
  const Eigen::Vector3d p_C = T_C_G * p_G;
  if (!(p_C.z() > 0.0)) return std::nullopt;
  const PinholeIntrinsics& k = camera.intrinsics;
  const double inv_z = 1.0 / p_C.z();
  const double u = k.fx * p_C.x() * inv_z + k.cx;
  const double v = k.fy * p_C.y() * inv_z + k.cy;
  if (!(u >= 0.0 && u < k.width && v >= 0.0 && v < k.height)) return std::nullopt;
  const Eigen::Vector3d centre = -(T_C_G.rotationMatrix().transpose() * T_C_G.translation());
  const Eigen::Vector3d ray = p_G - centre;
  const double distance = ray.norm();
  if (distance < landmark->minDistance() || distance > landmark->maxDistance()) {
    return std::nullopt;
  }
  const double view_cos = ray.dot(landmark->normal()) / distance;
  if (view_cos < min_view_cos) return std::nullopt;
  LandmarkProjection p;
  p.landmark = landmark;
  p.u = static_cast<float>(u);
  p.v = static_cast<float>(v);
  p.u_right = static_cast<float>(u - camera.bf() * inv_z);
  p.level = landmark->predictScale(distance, pyramid);
  p.view_cos = static_cast<float>(view_cos);
  return p;
}

int searchLocalLandmarks(Frame* frame, const std::vector<LandmarkProjection>& projections, float th,
                         const FeatureMatcherConfig& config, const ScalePyramid& pyramid) {
  const FrameFeatures& f = *frame->features;
  int matches = 0;
  for (const LandmarkProjection& p : projections) {
    Landmark* landmark = p.landmark;
    if (landmark == nullptr || landmark->bad()) continue;
    const float r = radiusByViewingCos(p.view_cos) * th * pyramid.scale(p.level);
    const std::vector<uint32_t> candidates =
        f.grid.featuresInArea(f.keypoints, p.u, p.v, r, p.level - 1, p.level);
    Best best;
    for (const uint32_t i : candidates) {
      const std::shared_ptr<Landmark>& held = frame->landmarks[i];
      if (held && held->numObservations() > 0) continue;
      if (f.right_u[i] > 0.0f && std::abs(p.u_right - f.right_u[i]) > r) continue;
      best.offer(hammingDistance(landmark->descriptor(), f.descriptors[i]), f.keypoints[i].octave,
                 static_cast<int>(i));
    }
    if (best.index < 0 || best.distance > config.max_distance) continue;
    if (best.level == best.second_level &&
        static_cast<float>(best.distance) > config.nn_ratio * static_cast<float>(best.second)) {
      continue;
    }
    frame->landmarks[static_cast<size_t>(best.index)] = landmark->shared_from_this();
    frame->outlier[static_cast<size_t>(best.index)] = 0;
    ++matches;
  }
  return matches;
}

int searchLastFrame(Frame* current, const Frame& last, float th, const TrackingCamera& camera,
                    const ScalePyramid& pyramid, const FeatureMatcherConfig& config) {
  const Transformationd& T_C_G = *current->T_C_G;
  const Transformationd& T_L_G = *last.T_C_G;
  const Eigen::Vector3d centre_in_last = T_L_G * T_C_G.inverse().translation();
  const bool forward = centre_in_last.z() > camera.baseline_m;
  const bool backward = -centre_in_last.z() > camera.baseline_m;
  const FrameFeatures& cf = *current->features;
  const FrameFeatures& lf = *last.features;
  const PinholeIntrinsics& k = camera.intrinsics;
  std::vector<std::pair<size_t, float>> matched;
  for (size_t i = 0; i < last.size(); ++i) {
    const std::shared_ptr<Landmark>& landmark = last.landmarks[i];
    if (!landmark || last.outlier[i] || landmark->bad()) continue;
    const Eigen::Vector3d p_C = T_C_G * landmark->position();
    if (!(p_C.z() > 0.0)) continue;
    const double u = k.fx * p_C.x() / p_C.z() + k.cx;
    const double v = k.fy * p_C.y() / p_C.z() + k.cy;
    if (!(u >= 0.0 && u < k.width && v >= 0.0 && v < k.height)) continue;
    const int octave = lf.keypoints[i].octave;
    const float radius = th * pyramid.scale(octave);
    std::vector<uint32_t> candidates;
    if (forward) {
      candidates = cf.grid.featuresInArea(cf.keypoints, static_cast<float>(u),
                                          static_cast<float>(v), radius, octave);
    } else if (backward) {
      candidates = cf.grid.featuresInArea(cf.keypoints, static_cast<float>(u),
                                          static_cast<float>(v), radius, 0, octave);
    } else {
      candidates = cf.grid.featuresInArea(cf.keypoints, static_cast<float>(u),
                                          static_cast<float>(v), radius, octave - 1, octave + 1);
    }
    const float u_right = static_cast<float>(u - camera.bf() / p_C.z());
    Best best;
    for (const uint32_t j : candidates) {
      const std::shared_ptr<Landmark>& held = current->landmarks[j];
      if (held && held->numObservations() > 0) continue;
      if (cf.right_u[j] > 0.0f && std::abs(u_right - cf.right_u[j]) > radius) continue;
      best.offer(hammingDistance(landmark->descriptor(), cf.descriptors[j]), cf.keypoints[j].octave,
                 static_cast<int>(j));
    }
    if (best.index < 0 || best.distance > config.max_distance) continue;
    const size_t j = static_cast<size_t>(best.index);
    current->landmarks[j] = landmark;
    current->outlier[j] = 0;
    matched.emplace_back(j, lf.keypoints[i].angle_deg - cf.keypoints[j].angle_deg);
  }
  if (!config.check_orientation) return static_cast<int>(matched.size());
  return filterByRotation(matched, [&](size_t j) { current->landmarks[j] = nullptr; });
}

int searchByBow(const Keyframe& keyframe, const FrameFeatures& frame,
                const FeatureMatcherConfig& config, std::vector<Landmark*>* matches) {
  matches->assign(frame.size(), nullptr);
  const FrameFeatures& kf = keyframe.features();
  std::vector<std::pair<size_t, float>> matched;
  forCommonNodes(
      kf.feature_vector, frame.feature_vector,
      [&](const std::vector<uint32_t>& kf_indices, const std::vector<uint32_t>& frame_indices) {
        for (const uint32_t i : kf_indices) {
          Landmark* landmark = keyframe.landmark(i);
          if (landmark == nullptr || landmark->bad()) continue;
          Best best;
          for (const uint32_t j : frame_indices) {
            if ((*matches)[j] != nullptr) continue;
            best.offer(hammingDistance(kf.descriptors[i], frame.descriptors[j]), 0,
                       static_cast<int>(j));
          }
          if (best.index < 0 || best.distance > kOrbDistanceLow) continue;
          if (static_cast<float>(best.distance) >=
              config.nn_ratio * static_cast<float>(best.second)) {
            continue;
          }
          const size_t j = static_cast<size_t>(best.index);
          (*matches)[j] = landmark;
          matched.emplace_back(j, kf.keypoints[i].angle_deg - frame.keypoints[j].angle_deg);
        }
      });
  if (!config.check_orientation) return static_cast<int>(matched.size());
  return filterByRotation(matched, [&](size_t j) { (*matches)[j] = nullptr; });
}

int searchByBow(const Keyframe& a, const Keyframe& b, const FeatureMatcherConfig& config,
                std::vector<Landmark*>* matches) {
  const FrameFeatures& fa = a.features();
  const FrameFeatures& fb = b.features();
  matches->assign(fa.size(), nullptr);
  std::vector<uint8_t> taken(fb.size(), 0);
  std::vector<std::pair<size_t, float>> matched;
  forCommonNodes(
      fa.feature_vector, fb.feature_vector,
      [&](const std::vector<uint32_t>& a_indices, const std::vector<uint32_t>& b_indices) {
        for (const uint32_t i : a_indices) {
          const Landmark* la = a.landmark(i);
          if (la == nullptr || la->bad()) continue;
          Best best;
          for (const uint32_t j : b_indices) {
            const Landmark* lb = b.landmark(j);
            if (taken[j] || lb == nullptr || lb->bad()) continue;
            best.offer(hammingDistance(fa.descriptors[i], fb.descriptors[j]), 0,
                       static_cast<int>(j));
          }
          if (best.index < 0 || best.distance > kOrbDistanceLow) continue;
          if (static_cast<float>(best.distance) >=
              config.nn_ratio * static_cast<float>(best.second)) {
            continue;
          }
          const size_t j = static_cast<size_t>(best.index);
          (*matches)[i] = b.landmark(j);
          taken[j] = 1;
          matched.emplace_back(i, fa.keypoints[i].angle_deg - fb.keypoints[j].angle_deg);
        }
      });
  if (!config.check_orientation) return static_cast<int>(matched.size());
  return filterByRotation(matched, [&](size_t i) { (*matches)[i] = nullptr; });
}

std::vector<size_t> consistentRotations(const std::vector<float>& rotations) {
  if (rotations.empty()) return {};
  auto wrap = [](float r) {
    r = std::fmod(r, 360.0f);
    return r < 0.0f ? r + 360.0f : r;
  };
  std::array<int, kRotationBins> histogram{};
  auto binOf = [&](float r) { return static_cast<int>(wrap(r) / kRotationBinDeg) % kRotationBins; };
  for (const float r : rotations) ++histogram[static_cast<size_t>(binOf(r))];
  // The densest window of three adjacent bins (circular); the first one on ties.
  auto window = [&](int b) {
    return histogram[static_cast<size_t>((b + kRotationBins - 1) % kRotationBins)] +
           histogram[static_cast<size_t>(b)] +
           histogram[static_cast<size_t>((b + 1) % kRotationBins)];
  };
  int centre = 0;
  for (int b = 1; b < kRotationBins; ++b) {
    if (window(b) > window(centre)) centre = b;
  }
  // The dominant change: circular mean of the changes in that window.
  double sin_sum = 0.0, cos_sum = 0.0;
  for (const float r : rotations) {
    const int d = (binOf(r) - centre + kRotationBins) % kRotationBins;
    if (d > 1 && d < kRotationBins - 1) continue;
    const double a = static_cast<double>(r) * M_PI / 180.0;
    sin_sum += std::sin(a);
    cos_sum += std::cos(a);
  }
  const float dominant = static_cast<float>(std::atan2(sin_sum, cos_sum) * 180.0 / M_PI);
  std::vector<size_t> keep;
  for (size_t i = 0; i < rotations.size(); ++i) {
    const float d = wrap(rotations[i] - dominant);
    if (std::min(d, 360.0f - d) <= kRotationToleranceDeg) keep.push_back(i);
  }
  return keep;
}

}  // namespace cblox
