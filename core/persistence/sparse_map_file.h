#pragma once

// The tracker's map on disk (README, "Tracker map format"): a directory holding
//   tracker_map.cbtm                 the index, written last: map epoch, camera, poses,
//                                    covisibility, spanning tree, loop edges, landmarks
//   keyframes_e<E>_g<G>.cbkf         keyframe features (keypoints, descriptors, stereo
//                                    depth), one file per checkpoint generation G holding the
//                                    keyframes that were new then; never rewritten
//   keyframe_ids.lease               ids handed out beyond the last checkpoint (id_lease.h)
// Every file has the 32-byte map file header (map_file_header.h: magic, version, length,
// XXH64) and a zstd section (zstd_blob.h). Only the files the index lists are trusted.

#include <cstdint>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "core/geometry/pinhole_camera.h"
#include "core/tracking/sparse_map_snapshot.h"

namespace cblox {

/// Newest tracker map format version this build writes and reads (both file kinds).
inline constexpr uint32_t kTrackerMapVersion = 1;
inline constexpr char kTrackerMapFileName[] = "tracker_map.cbtm";
inline constexpr std::string_view kTrackerMapMagic = "CBLOXTRK";
inline constexpr std::string_view kKeyframeChunkMagic = "CBLOXKFS";
/// Keyframe index entry for a culled keyframe (its features are not kept).
inline constexpr uint32_t kNoKeyframeChunk = std::numeric_limits<uint32_t>::max();

/// The camera a tracker map was built in: rectified intrinsics and the (real or virtual)
/// stereo baseline, metres.
struct TrackerMapCamera {
  PinholeIntrinsics intrinsics;
  double baseline_m = 0.0;
};

/// The sparse map of one map epoch as a tracker saves and resumes it.
struct TrackerMapState {
  uint64_t generation = 0;  ///< of the checkpoint that wrote it (0 before the first)
  int32_t map_epoch = 0;
  TrackerMapCamera camera;
  SparseMapSnapshot map;
};

/// A keyframe features file the index lists: name, whole-file size and payload XXH64.
struct KeyframeChunkRef {
  std::string file_name;
  uint64_t file_size = 0;
  uint64_t payload_xxh64 = 0;
};

/// tracker_map.cbtm's content: the state without features, which chunk holds each keyframe's
/// features (kNoKeyframeChunk for culled keyframes), and the chunk files.
struct TrackerMapIndex {
  TrackerMapState state;  ///< every KeyframeSnapshot::features is null
  std::vector<KeyframeChunkRef> chunks;
  std::vector<uint32_t> keyframe_chunk;  ///< one per keyframe
};

/// "keyframes_e<epoch>_g<generation>.cbkf". Thread-safe (pure).
std::string keyframeChunkFileName(int32_t map_epoch, uint64_t generation);

/// The index's payload (before sealMapFile). Preconditions: keyframe_chunk has one entry per
/// keyframe, every entry is kNoKeyframeChunk or < chunks.size(). Thread-safe (pure).
std::string encodeTrackerMapIndex(const TrackerMapIndex& index);
/// Parses an index payload: every count bounded by the bytes that remain before anything is
/// allocated, no bytes left over, poses finite with unit quaternions, chunk entries in
/// range (kNoKeyframeChunk exactly for culled keyframes). Returns std::nullopt with what is
/// wrong in *error (if non-null). Thread-safe (pure).
std::optional<TrackerMapIndex> decodeTrackerMapIndex(std::string_view payload, std::string* error);

/// A chunk file's payload holding the features of `keyframes` (non-null, good keyframes).
/// Thread-safe (pure).
std::string encodeKeyframeChunk(const std::vector<const KeyframeSnapshot*>& keyframes);
/// Parses a chunk payload into (keyframe id -> features without grid or BoW), with the same
/// bounds as decodeTrackerMapIndex and no id twice. Thread-safe (pure).
std::optional<std::map<KeyframeId, std::shared_ptr<FrameFeatures>>> decodeKeyframeChunk(
    std::string_view payload, std::string* error);

/// XXH64 of what never changes in a keyframe: id, frame id, time stamp and features (as a
/// chunk file encodes them). Equal digests = bit-identical features. Thread-safe (pure).
uint64_t keyframeFeaturesDigest(const KeyframeSnapshot& keyframe);
/// XXH64 of what changes in a keyframe, as the index encodes it: pose, culled flag, parent,
/// T_parent_this, connections and loop edges. Thread-safe (pure).
uint64_t keyframeStateDigest(const KeyframeSnapshot& keyframe);
/// XXH64 of every landmark as the index encodes it, and the change index (not the next
/// landmark id, which a resume may raise to the id lease). Equal digests (and equal keyframe
/// digests) = bit-identical maps. Thread-safe (pure).
uint64_t landmarksDigest(const SparseMapSnapshot& map);

/// Whether `dir` holds a tracker map index (it may still be unreadable).
bool hasTrackerMap(const std::string& dir);

/// Reads the tracker map in `dir`: the index (readMapFile: header, version, checksum), then
/// every chunk it lists (size and XXH64 as listed), then SparseMapSnapshot::validate (keypoint
/// octaves are checked on restore, against the tracker's pyramid). Returns std::nullopt with
/// "<path>: <what is wrong>" in *error (if non-null). With `index` (non-null), it also gets
/// the index's generation, epoch, chunks and keyframe_chunk (for
/// TrackerMapCheckpointer::adoptLoaded; its state's map stays empty). Thread-safe (no shared
/// state).
std::optional<TrackerMapState> loadTrackerMap(const std::string& dir, std::string* error,
                                              TrackerMapIndex* index = nullptr);

}  // namespace cblox
