#pragma once

#include <map>
#include <set>
#include <span>

#include "core/features/scale_pyramid.h"
#include "core/geometry/se3.h"
#include "core/tracking/sparse_map.h"

namespace cblox {

/// Keyframe poses T_C_G by keyframe.
using KeyframePoses = std::map<const Keyframe*, Transformationd>;

/// Poses an optimiser solved from a copy of the map read earlier, applied to the map as it is
/// now. The loop closer reads the essential graph under the map's exclusive lock, releases
/// it while the graph is solved (tracking and local mapping go on), and takes it again to
/// apply the solution with this; ORB-SLAM2 holds the lock throughout. The caller holds the
/// map's exclusive lock.
///
/// `keyframes[v]` had the pose `read_T_C_G[v]` when the problem was read; the solution gives
/// it `solved_T_C_G[v]` (the three spans have the same length, else std::invalid_argument):
///  - a good keyframe that moved since it was read (a local BA applied meanwhile) keeps that
///    change on top of the solution: T_C_G = (T_C_G_now * read_T_C_G^-1) * solved_T_C_G;
///    bad ones are left as they are;
///  - keyframes made since (not in `keyframes`) follow their parent
///    (newKeyframesFollowTheirParent);
///  - every good landmark keeps its position in the frame of the keyframe that placed it, or
///    of the one `anchor_of` names for it (a landmark moved with that keyframe before the
///    problem was read), and moves with that keyframe; landmarks of a bad keyframe stay.
void applySolvedPoses(SparseMap* map, std::span<Keyframe* const> keyframes,
                      std::span<const Transformationd> read_T_C_G,
                      std::span<const Transformationd> solved_T_C_G,
                      const std::map<LandmarkId, const Keyframe*>& anchor_of,
                      const ScalePyramid& pyramid);

/// Every good landmark not in `skip` keeps its position in the frame of the keyframe that
/// placed it, or of the one `anchor_of` names for it, and moves with that keyframe: `before`
/// holds the keyframes' poses before they moved; a landmark whose keyframe is bad or absent
/// from `before` stays. The caller holds the map's exclusive lock.
void landmarksFollowTheirKeyframe(SparseMap* map, const KeyframePoses& before,
                                  const std::map<LandmarkId, const Keyframe*>& anchor_of,
                                  const std::set<const Landmark*>& skip,
                                  const ScalePyramid& pyramid);

/// Keyframes absent from `before` (made while the map's lock was released for an
/// optimisation) whose parent is in it follow their parent: `before` holds the poses the
/// optimisation's keyframes had just before it was applied, and each such keyframe keeps its
/// pose relative to its parent, T_C_G = (T_C_G_now * T_Cparent_G_before^-1) *
/// T_Cparent_G_now. Ids increase along the spanning tree, so a parent is placed before its
/// children. Adds their previous poses to `before`. The caller holds the map's exclusive lock.
void newKeyframesFollowTheirParent(const SparseMap& map, KeyframePoses* before);

}  // namespace cblox
