#pragma once

// cblox-map-verify's view of a tracker checkpoint directory (README "Tracker map format"):
// the map loaded and checked as a resuming tracker loads it, described as JSON.

#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace cblox {

/// Loads the tracker map in `dir` (loadTrackerMap: every checksum, the chunks the index lists,
/// consistency) and the id lease, and describes them: generation, map epoch, camera, per
/// keyframe id / culled / chunk file / features and state digests (keyframeFeaturesDigest,
/// keyframeStateDigest, hex), the landmarks' count and digest, the lease, and the files the
/// index does not list. Problems (an unreadable map or lease) go to *problems.
nlohmann::json describeTrackerMap(const std::string& dir, std::vector<std::string>* problems);

}  // namespace cblox
