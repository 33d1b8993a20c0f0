#pragma once

// A copy of the sparse SLAM map as plain data: what the tracker's checkpoint saves and what a
// resumed tracker restores (core/persistence/sparse_map_file.h writes and reads it). Pointers
// of the live map become ids; everything a restored map needs to continue exactly is here
// (poses, covisibility weights, spanning tree, loop edges, landmark observations, descriptors,
// viewing ranges, tracking statistics). What the map rebuilds itself is not: the keyframes'
// neighbour order and children (from the connections and parents), the feature grids and the
// BoW vectors (FrameBuilder::index, from the keypoints and the vocabulary).

#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "core/features/orb_descriptor.h"
#include "core/geometry/se3.h"
#include "core/tracking/frame_features.h"
#include "core/tracking/keyframe_order.h"
#include "core/tracking/landmark.h"

namespace cblox {

class SparseMap;

/// One keyframe of a snapshot.
struct KeyframeSnapshot {
  KeyframeId id = 0;
  uint64_t frame_id = 0;
  int64_t timestamp_ns = 0;
  Transformationd T_C_G;
  /// Culled. A culled keyframe keeps its pose, parent and T_parent_this, not its features.
  bool bad = false;
  /// Keyframe::updateConnections has not yet chosen a spanning-tree parent.
  bool first_connection_pending = true;
  KeyframeId parent = -1;         ///< -1: none
  Transformationd T_parent_this;  ///< meaningful when bad
  std::vector<std::pair<KeyframeId, int>> connections;  ///< (neighbour, weight), ascending id
  std::vector<KeyframeId> loop_edges;                    ///< ascending
  /// The features (never null; empty for a culled keyframe). Their grid and BoW vector are
  /// rebuilt on restore when missing.
  std::shared_ptr<const FrameFeatures> features;
};

/// One (good) landmark of a snapshot.
struct LandmarkSnapshot {
  LandmarkId id = 0;
  Eigen::Vector3d p_G = Eigen::Vector3d::Zero();
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();
  /// Landmark's raw distance range (minDistance() / maxDistance() are 0.8 / 1.2 of these).
  double min_distance = 0.0, max_distance = 0.0;
  OrbDescriptor descriptor{};
  KeyframeId reference = -1;  ///< -1: none
  KeyframeId first_keyframe_id = 0;
  int visible = 1, found = 1;
  std::vector<std::pair<KeyframeId, uint32_t>> observations;  ///< (keyframe, feature index)
};

/// The whole sparse map. Keyframe ids are 0 .. keyframes.size() - 1 (index = id); the map
/// continues with keyframe id keyframes.size() and landmark id next_landmark_id.
struct SparseMapSnapshot {
  std::vector<KeyframeSnapshot> keyframes;  ///< every keyframe ever added, by id
  std::vector<LandmarkSnapshot> landmarks;  ///< good landmarks, ascending id
  LandmarkId next_landmark_id = 0;
  int change_index = 0;

  /// Empty when the snapshot is a consistent map, otherwise the first thing wrong: keyframe
  /// ids not 0..n-1, a non-finite pose or position, feature vectors of different lengths, a
  /// keypoint octave outside [0, pyramid_levels), a parent / neighbour / loop edge / reference
  /// that is not a keyframe of the snapshot (or the keyframe itself), a weight < 1, an edge
  /// whose other end does not list it with the same weight, a landmark id not below
  /// next_landmark_id or not ascending, an observation of a culled keyframe or of a feature
  /// index out of range, two landmarks observed by the same feature. Thread-safe (pure).
  std::string validate(int pyramid_levels) const;
};

/// The features of a keyframe that has none (culled, or an id stand-in): one shared empty set.
const std::shared_ptr<const FrameFeatures>& emptyFrameFeatures();

/// Copies `map` into a snapshot. The features are shared, not copied. The caller holds the
/// map's shared lock.
SparseMapSnapshot takeSparseMapSnapshot(const SparseMap& map);

}  // namespace cblox
