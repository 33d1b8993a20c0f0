#include "core/tracking/landmark.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "core/features/scale_pyramid.h"
#include "core/tracking/keyframe.h"

namespace cblox {

Landmark::Landmark(LandmarkId id_, const Eigen::Vector3d& p_G, Keyframe* reference_keyframe)
    : id(id_), p_G_(p_G), reference_keyframe_(reference_keyframe) {}

void Landmark::addObservation(Keyframe* keyframe, uint32_t index, bool stereo) {
  if (!observations_.emplace(keyframe, index).second) return;
  num_obs_ += stereo ? 2 : 1;
}

bool Landmark::eraseObservation(Keyframe* keyframe, bool stereo) {
  if (observations_.erase(keyframe) > 0) {
    num_obs_ -= stereo ? 2 : 1;
    if (reference_keyframe_ == keyframe) {
      reference_keyframe_ = observations_.empty() ? nullptr : observations_.begin()->first;
    }
  }
  return num_obs_ <= 2;
}

int Landmark::indexIn(const Keyframe* keyframe) const {
  const auto it = observations_.find(const_cast<Keyframe*>(keyframe));
  return it == observations_.end() ? -1 : static_cast<int>(it->second);
}

void Landmark::updateDescriptor() {
  std::vector<const OrbDescriptor*> descriptors;
  descriptors.reserve(observations_.size());
  for (const auto& [keyframe, index] : observations_) {
    if (!keyframe->bad()) descriptors.push_back(&keyframe->features().descriptors[index]);
  }
  if (descriptors.empty()) return;
  const size_t n = descriptors.size();
  size_t best = 0;
  int best_median = 257;
  std::vector<int> distances(n);
  for (size_t i = 0; i < n; ++i) {
    for (size_t j = 0; j < n; ++j) distances[j] = hammingDistance(*descriptors[i], *descriptors[j]);
    std::nth_element(distances.begin(), distances.begin() + static_cast<long>((n - 1) / 2),
                     distances.end());
    const int median = distances[(n - 1) / 2];
    if (median < best_median) {
      best_median = median;
      best = i;
    }
  }
  descriptor_ = *descriptors[best];
}

void Landmark::updateNormalAndDepth(const ScalePyramid& pyramid) {
  if (observations_.empty() || reference_keyframe_ == nullptr) return;
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  int n = 0;
  for (const auto& [keyframe, index] : observations_) {
    const Eigen::Vector3d d = p_G_ - keyframe->T_G_C().translation();
    const double norm = d.norm();
    if (norm > 0.0) {
      sum += d / norm;
      ++n;
    }
  }
  if (n > 0) normal_ = sum / n;
  const int index = indexIn(reference_keyframe_);
  if (index < 0) return;
  const double distance = (p_G_ - reference_keyframe_->T_G_C().translation()).norm();
  const int level = reference_keyframe_->features().keypoints[static_cast<size_t>(index)].octave;
  const double level_scale = pyramid.scale(level);
  max_distance_ = distance * level_scale;
  min_distance_ = max_distance_ / pyramid.scale(pyramid.numLevels() - 1);
}

int Landmark::predictScale(double distance, const ScalePyramid& pyramid) const {
  if (!(distance > 0.0) || !(max_distance_ > 0.0)) return 0;
  const double ratio = max_distance_ / distance;
  const int level = static_cast<int>(std::ceil(std::log(ratio) / std::log(pyramid.scaleFactor())));
  return std::clamp(level, 0, pyramid.numLevels() - 1);
}

double Landmark::foundRatio() const {
  const int v = visible();
  return v > 0 ? static_cast<double>(found()) / v : 1.0;
}

void Landmark::restoreDerived(const OrbDescriptor& descriptor, const Eigen::Vector3d& normal,
                              double min_distance, double max_distance, int visible,
                              int found) {
  descriptor_ = descriptor;
  normal_ = normal;
  min_distance_ = min_distance;
  max_distance_ = max_distance;
  visible_.store(visible, std::memory_order_relaxed);
  found_.store(found, std::memory_order_relaxed);
}

}  // namespace cblox
