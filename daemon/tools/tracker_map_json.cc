#include "daemon/tools/tracker_map_json.h"

#include <cinttypes>
#include <cstdio>
#include <filesystem>
#include <set>

#include "core/persistence/id_lease.h"
#include "core/persistence/sparse_map_file.h"

namespace cblox {

namespace {

std::string hex(uint64_t v) {
  char text[24];
  std::snprintf(text, sizeof(text), "%016" PRIx64, v);
  return text;
}

}  // namespace

nlohmann::json describeTrackerMap(const std::string& dir, std::vector<std::string>* problems) {
  nlohmann::json out;
  out["dir"] = dir;
  out["kind"] = "tracker";
  std::string error;
  const std::optional<IdLease> lease = readIdLease(dir, &error);
  if (!error.empty()) problems->push_back(error);
  out["lease"] = lease ? nlohmann::json{{"map_epoch", lease->map_epoch},
                                        {"keyframe_floor", lease->keyframe_floor},
                                        {"landmark_floor", lease->landmark_floor}}
                       : nlohmann::json();
  TrackerMapIndex index;
  const std::optional<TrackerMapState> state = loadTrackerMap(dir, &error, &index);
  if (!state) {
    problems->push_back(error);
    return out;
  }
  out["generation"] = state->generation;
  out["map_epoch"] = state->map_epoch;
  const PinholeIntrinsics& k = state->camera.intrinsics;
  out["camera"] = {{"fx", k.fx}, {"fy", k.fy}, {"cx", k.cx}, {"cy", k.cy},
                   {"width", k.width}, {"height", k.height},
                   {"baseline_m", state->camera.baseline_m}};
  nlohmann::json keyframes = nlohmann::json::array();
  size_t good = 0;
  for (size_t i = 0; i < state->map.keyframes.size(); ++i) {
    const KeyframeSnapshot& kf = state->map.keyframes[i];
    const uint32_t chunk = index.keyframe_chunk[i];
    good += kf.bad ? 0 : 1;
    keyframes.push_back({{"id", kf.id},
                         {"bad", kf.bad},
                         {"features", kf.features->size()},
                         {"chunk", chunk == kNoKeyframeChunk ? "" : index.chunks[chunk].file_name},
                         {"features_digest", hex(keyframeFeaturesDigest(kf))},
                         {"state_digest", hex(keyframeStateDigest(kf))}});
  }
  out["keyframes"] = std::move(keyframes);
  out["good_keyframes"] = good;
  out["landmarks"] = state->map.landmarks.size();
  out["next_landmark_id"] = state->map.next_landmark_id;
  out["landmarks_digest"] = hex(landmarksDigest(state->map));
  std::set<std::string> listed = {kTrackerMapFileName, kIdLeaseFileName};
  nlohmann::json chunks = nlohmann::json::array();
  for (const KeyframeChunkRef& c : index.chunks) {
    listed.insert(c.file_name);
    chunks.push_back({{"file", c.file_name}, {"file_size", c.file_size},
                      {"xxh64", hex(c.payload_xxh64)}});
  }
  out["chunks"] = std::move(chunks);
  std::vector<std::string> unlisted;
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator(dir, ec)) {
    const std::string name = entry.path().filename().string();
    if (!listed.contains(name)) unlisted.push_back(name);
  }
  std::sort(unlisted.begin(), unlisted.end());
  out["unlisted_files"] = unlisted;
  out["verified"] = "index, chunks, consistency";
  return out;
}

}  // namespace cblox
