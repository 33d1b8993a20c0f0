#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <set>
#include <utility>
#include <vector>

#include "core/geometry/se3.h"
#include "core/tracking/frame_features.h"
#include "core/tracking/keyframe_order.h"

namespace cblox {

class Landmark;

/// A keyframe of the sparse map (ORB-SLAM2's KeyFrame): the features of one frame, its pose,
/// the landmark each feature observes, the covisibility graph edges (keyframes sharing
/// landmarks, weighted by how many) and the spanning tree.
///
/// Thread-safety: id, frame_id, timestamp_ns and the features are immutable. Everything
/// else is guarded by the SparseMap's mutex (shared lock to read, exclusive to write).
/// Keyframes are never freed while their SparseMap lives (a culled keyframe is only marked
/// bad), so raw Keyframe pointers held under the map's lock stay valid.
class Keyframe {
 public:
  Keyframe(KeyframeId id, uint64_t frame_id, int64_t timestamp_ns,
           std::shared_ptr<const FrameFeatures> features, const Transformationd& T_C_G);

  const KeyframeId id;
  const uint64_t frame_id;
  const int64_t timestamp_ns;

  const FrameFeatures& features() const { return *features_; }
  const std::shared_ptr<const FrameFeatures>& sharedFeatures() const { return features_; }

  /// Pose: world (G) to camera, and its inverse (camera centre = T_G_C().translation()).
  const Transformationd& T_C_G() const { return T_C_G_; }
  const Transformationd& T_G_C() const { return T_G_C_; }
  void setPose(const Transformationd& T_C_G) {
    T_C_G_ = T_C_G;
    T_G_C_ = T_C_G.inverse();
  }

  /// Landmark observed by feature i (nullptr: none). One entry per feature.
  Landmark* landmark(size_t i) const { return landmarks_[i]; }
  const std::vector<Landmark*>& landmarks() const { return landmarks_; }
  void setLandmark(size_t i, Landmark* landmark) { landmarks_[i] = landmark; }
  /// Good (not bad) landmarks observed; with min_observations > 0 only those with at least
  /// that many observations, a stereo observation counting 2 (ORB-SLAM2's
  /// TrackedMapPoints and MapPoint::Observations).
  int numTrackedLandmarks(int min_observations = 0) const;

  /// Covisibility: rebuilds this keyframe's edges from its landmarks' observations (weight =
  /// shared landmarks; edges of weight >= 15 kept, or the single best one if none, like
  /// ORB-SLAM2's UpdateConnections) and updates the other ends. The first call also makes
  /// the best neighbour the spanning-tree parent (unless this is the first keyframe). The
  /// caller holds the map's exclusive lock (the counts live in the other keyframes).
  void updateConnections();
  /// Neighbours by decreasing weight.
  const std::vector<Keyframe*>& covisibleByWeight() const { return ordered_neighbours_; }
  /// The best n neighbours (fewer if there are not as many).
  std::vector<Keyframe*> bestCovisible(size_t n) const;
  /// Neighbours with weight >= w.
  std::vector<Keyframe*> covisibleWithWeightAtLeast(int w) const;
  int weight(const Keyframe* other) const;
  const std::map<Keyframe*, int, KeyframeIdLess>& connections() const { return connections_; }
  /// Adds or updates one edge end (used by updateConnections of the other keyframe); the
  /// neighbour order is updated in place (an unchanged weight leaves it as it is).
  void addConnection(Keyframe* other, int weight);
  void eraseConnection(Keyframe* other);

  /// Spanning tree.
  Keyframe* parent() const { return parent_; }
  const std::set<Keyframe*, KeyframeIdLess>& children() const { return children_; }
  void changeParent(Keyframe* parent);
  /// Loop edges (kept so loop keyframes are never culled).
  const std::set<Keyframe*, KeyframeIdLess>& loopEdges() const { return loop_edges_; }
  void addLoopEdge(Keyframe* other) { loop_edges_.insert(other); }

  /// Culled: bad keyframes are skipped by every search and graph walk.
  bool bad() const { return bad_; }
  /// Culls the keyframe: removes its edges and landmark observations, and hands its
  /// children to other parents (ORB-SLAM2's SetBadFlag). No effect on the first keyframe or
  /// on keyframes with loop edges. Returns the landmarks left with too few observations (the
  /// caller retires them). T_Parent_This is kept so the poses of frames that referenced it
  /// can still be recovered.
  std::vector<Landmark*> cull();
  /// Pose relative to the parent at the time of culling (valid when bad()).
  const Transformationd& T_parent_this() const { return T_parent_this_; }
  /// updateConnections has not yet chosen the spanning-tree parent.
  bool firstConnectionPending() const { return first_connection_; }

  /// Restores the graph state a snapshot recorded (SparseMap::restore only): this end of
  /// each connection (the other end restores its own), the parent (joined as its child unless
  /// `bad`), the loop edges, the culled flag and T_parent_this.
  void restoreGraph(const std::vector<std::pair<Keyframe*, int>>& connections, Keyframe* parent,
                    const std::vector<Keyframe*>& loop_edges, bool first_connection_pending,
                    bool bad, const Transformationd& T_parent_this);

  /// Bookkeeping of the threads (keyframe/frame ids of the last use), ORB-SLAM2 style.
  uint64_t track_reference_frame = 0;
  /// The tracker's count of the current frame's landmarks this keyframe observes, valid when
  /// track_counted_frame is the tracker's current frame.
  uint64_t track_counted_frame = 0;
  int track_shared_landmarks = 0;
  KeyframeId fuse_target_for_keyframe = -1;
  KeyframeId ba_local_for_keyframe = -1;
  KeyframeId ba_fixed_for_keyframe = -1;
  KeyframeId loop_query = -1;
  uint64_t reloc_query = 0;

 private:
  // ordered_neighbours_ / ordered_weights_ from connections_: decreasing weight, ties by id.
  void rebuildOrder();
  void removeFromOrder(Keyframe* other);

  std::shared_ptr<const FrameFeatures> features_;
  Transformationd T_C_G_, T_G_C_;
  std::vector<Landmark*> landmarks_;
  std::map<Keyframe*, int, KeyframeIdLess> connections_;
  std::vector<Keyframe*> ordered_neighbours_;
  std::vector<int> ordered_weights_;
  bool first_connection_ = true;
  // updateConnections() of another keyframe counts its landmarks shared with this one here.
  uint64_t connection_count_stamp_ = 0;
  int connection_count_ = 0;
  Keyframe* parent_ = nullptr;
  std::set<Keyframe*, KeyframeIdLess> children_;
  std::set<Keyframe*, KeyframeIdLess> loop_edges_;
  bool bad_ = false;
  Transformationd T_parent_this_;
};

}  // namespace cblox
