#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

#include "core/geometry/se3.h"
#include "core/tracking/frame_features.h"
#include "core/tracking/landmark.h"

namespace cblox {

class Keyframe;

/// One frame as the tracking thread sees it: its features (shared with the keyframe made
/// from it, if any), the landmark matched to each feature, and its pose once tracked.
/// Owned by the tracking thread (not thread-safe). Landmarks are held by shared_ptr so a
/// landmark retired by local mapping meanwhile stays valid here (check bad()); reading a
/// landmark's mutable fields needs the SparseMap's shared lock.
struct Frame {
  uint64_t id = 0;
  int64_t timestamp_ns = 0;
  std::shared_ptr<const FrameFeatures> features;
  /// Matched landmark per feature (nullptr: none), and whether the last pose optimisation
  /// classified that match an outlier.
  std::vector<std::shared_ptr<Landmark>> landmarks;
  std::vector<uint8_t> outlier;
  /// World-to-camera pose, once known.
  std::optional<Transformationd> T_C_G;
  /// Keyframe this frame was tracked against (shares the most landmarks).
  Keyframe* reference_keyframe = nullptr;

  Frame() = default;
  Frame(uint64_t frame_id, int64_t timestamp, std::shared_ptr<const FrameFeatures> f)
      : id(frame_id),
        timestamp_ns(timestamp),
        features(std::move(f)),
        landmarks(features->size()),
        outlier(features->size(), 0) {}

  size_t size() const { return landmarks.size(); }
  /// Matches that are not outliers.
  int numInlierMatches() const {
    int n = 0;
    for (size_t i = 0; i < landmarks.size(); ++i) n += (landmarks[i] && !outlier[i]) ? 1 : 0;
    return n;
  }
  void clearMatches() {
    std::fill(landmarks.begin(), landmarks.end(), nullptr);
    std::fill(outlier.begin(), outlier.end(), 0);
  }
};

}  // namespace cblox
