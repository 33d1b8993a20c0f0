#pragma once

#include <vector>

#include "core/features/fast_grid_detector.h"

namespace cblox {

/// ORB-SLAM2's quadtree distribution (ORBextractor::DistributeOctTree): spreads at most
/// `wanted` corners evenly over the area [min_x, max_x) x [min_y, max_y) (level pixels).
///
/// The area starts as round(width / height) (at least 1) side-by-side nodes; nodes with no
/// corner are dropped. While there are fewer than `wanted` nodes and some node holds more than
/// one corner: if splitting every such node into its four quadrants (halves rounded up; empty
/// quadrants dropped) cannot give more than `wanted` nodes (nodes + 3 * splittable <= wanted),
/// all are split; otherwise nodes are split largest first (most corners; ties in node order),
/// one at a time, until there are `wanted` nodes. Each node keeps its highest-response corner
/// (the first one on ties).
///
/// Differences from ORB-SLAM2, for robustness: ORB-SLAM2 also stops when a pass leaves the
/// node count unchanged (every split node had all its corners in one quadrant), which can end
/// far below `wanted` when corners are clustered; here splitting goes on while a node holds
/// more than one corner. ORB-SLAM2 keeps the up to 3 extra nodes of the last split; here the
/// weakest children of that split are dropped (and, if there are more initial nodes than
/// wanted, the weakest nodes), so at most `wanted` corners are returned.
///
/// Returns indices into `corners`, one per node, in node order. Corners outside the area are
/// ignored; corners at the same pixel share a node. Thread-safe (pure).
std::vector<int> distributeQuadtree(const std::vector<LevelCorner>& corners, int min_x, int max_x,
                                    int min_y, int max_y, int wanted);

}  // namespace cblox
