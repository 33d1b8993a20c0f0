#include "daemon/tracker/tracker_resume.h"

#include <algorithm>
#include <filesystem>

#include "core/tracking/sparse_map.h"

namespace cblox {

std::optional<TrackerResume> loadTrackerResume(const std::string& dir, std::string* error) {
  error->clear();
  std::optional<IdLease> lease = readIdLease(dir, error);
  if (!error->empty()) return std::nullopt;
  TrackerResume resume;
  if (hasTrackerMap(dir)) {
    resume.map = loadTrackerMap(dir, error, &resume.index);
    if (!resume.map) return std::nullopt;
  }
  if (!resume.map && !lease) return std::nullopt;
  // Ids are keyed by the mapper below 2^40 (core/mapping/map_epoch_key.h); a lease far above
  // the saved map (many keyframes published after it: checkpoints failing for long) is not
  // continued either, since every skipped id would cost a stand-in keyframe.
  const bool lease_fits =
      !lease || !resume.map ||
      (lease->map_epoch == resume.map->map_epoch &&
       lease->keyframe_floor <= static_cast<int64_t>(resume.map->map.keyframes.size()) +
                                    SparseMap::kMaxSkippedKeyframeIds &&
       lease->landmark_floor < (uint64_t{1} << 40));
  if (resume.map && lease_fits) {
    const SparseMapSnapshot& map = resume.map->map;
    resume.map_epoch = resume.map->map_epoch;
    resume.keyframe_floor =
        std::max<int64_t>(static_cast<int64_t>(map.keyframes.size()), lease ? lease->keyframe_floor : 0);
    resume.landmark_floor = std::max(map.next_landmark_id, lease ? lease->landmark_floor : 0);
    size_t good = 0;
    for (const KeyframeSnapshot& k : map.keyframes) good += k.bad ? 0 : 1;
    resume.description = "resuming the map of epoch " + std::to_string(resume.map_epoch) + " in " +
                         dir + " (checkpoint " + std::to_string(resume.map->generation) + ": " +
                         std::to_string(good) + " keyframes, " +
                         std::to_string(map.landmarks.size()) + " landmarks); new keyframe ids from " +
                         std::to_string(resume.keyframe_floor);
    return resume;
  }
  const int32_t newest = std::max(resume.map ? resume.map->map_epoch : 0, lease->map_epoch);
  if (newest >= (int32_t{1} << 22) - 1) {  // core/mapping/map_epoch_key.h's kMaxMapEpoch
    *error = dir + ": map epoch " + std::to_string(newest) + " leaves no epoch to start";
    return std::nullopt;
  }
  resume.description =
      (resume.map ? "the map of epoch " + std::to_string(resume.map->map_epoch) + " in " + dir +
                        " is behind the ids published (id lease: epoch " +
                        std::to_string(lease->map_epoch) + ", keyframe ids below " +
                        std::to_string(lease->keyframe_floor) + ")"
                  : "no map saved in " + dir + " but ids published in epoch " +
                        std::to_string(lease->map_epoch)) +
      ": starting a new map in epoch " + std::to_string(newest + 1);
  resume.map.reset();
  resume.index = {};
  resume.map_epoch = newest + 1;
  return resume;
}

IdLeaseKeeper::IdLeaseKeeper(std::string dir, std::optional<IdLease> current,
                             int64_t keyframe_margin, uint64_t landmark_margin)
    : dir_(std::move(dir)),
      lease_(current),
      keyframe_margin_(keyframe_margin),
      landmark_margin_(landmark_margin) {}

bool IdLeaseKeeper::cover(int32_t epoch, int64_t id, uint64_t newest_landmark, std::string* error) {
  if (lease_ && lease_->map_epoch == epoch && id < lease_->keyframe_floor &&
      newest_landmark < lease_->landmark_floor) {
    return true;
  }
  IdLease next{epoch, id + keyframe_margin_, newest_landmark + landmark_margin_};
  if (lease_ && lease_->map_epoch == epoch) {
    next.keyframe_floor = std::max(next.keyframe_floor, lease_->keyframe_floor);
    next.landmark_floor = std::max(next.landmark_floor, lease_->landmark_floor);
  }
  std::error_code ec;
  std::filesystem::create_directories(dir_, ec);
  if (!writeIdLease(dir_, next, error)) return false;
  lease_ = next;
  ++renewals_;
  return true;
}

}  // namespace cblox
