#include "core/persistence/sparse_map_file.h"

#include <cstdio>
#include <filesystem>
#include <set>

#include "core/persistence/byte_codec.h"
#include "core/persistence/map_file_header.h"
#include "core/persistence/pose_codec.h"
#include "core/persistence/zstd_blob.h"

namespace cblox {

using persistence_detail::ByteReader;
using persistence_detail::ByteWriter;
using persistence_detail::readPose;
using persistence_detail::writePose;

namespace {

constexpr int kZstdLevel = 3;
constexpr size_t kMaxFileNameBytes = 255;
// Smallest encoded records, to bound counts by the bytes that remain.
constexpr size_t kMinChunkRefBytes = 4 + 8 + 8;
constexpr size_t kMinKeyframeBytes = 8 + 8 + 8 + 56 + 1 + 8 + 56 + 4 + 4 + 4;
constexpr size_t kConnectionBytes = 12, kLoopEdgeBytes = 8, kObservationBytes = 12;
constexpr size_t kMinLandmarkBytes = 8 + 24 + 24 + 16 + 32 + 8 + 8 + 4 + 4 + 4;
constexpr size_t kMinChunkKeyframeBytes = 8 + 4;
constexpr size_t kFeatureBytes = 4 * 4 + 4 + 32 + 4 + 4;
constexpr uint8_t kBadFlag = 1, kFirstConnectionPendingFlag = 2;

void writeDescriptor(ByteWriter& w, const OrbDescriptor& d) {
  for (const uint64_t word : d.words) w.u64(word);
}
void readDescriptor(ByteReader& r, OrbDescriptor* d) {
  for (uint64_t& word : d->words) r.u64(&word);
}

// Reads a count and checks it against the bytes that remain (each item at least min_bytes).
bool readCount(ByteReader& r, size_t min_bytes, uint64_t* count, const std::string& what,
               std::string* error) {
  uint32_t n = 0;
  if (!r.u32(&n)) {
    *error = "truncated at the " + what + " count";
    return false;
  }
  if (n > r.remaining() / min_bytes) {
    *error = what + " count " + std::to_string(n) + " out of bounds for the " +
             std::to_string(r.remaining()) + " bytes that remain";
    return false;
  }
  *count = n;
  return true;
}

template <typename T>
std::optional<T> failed(std::string* error, const std::string& message) {
  if (error != nullptr) *error = message;
  return std::nullopt;
}

// One keyframe's record in a chunk file: id, feature count, then per feature its keypoint,
// descriptor, right u and depth.
void encodeFeatures(ByteWriter& w, const KeyframeSnapshot& k) {
  const FrameFeatures& f = *k.features;
  w.i64(k.id);
  w.u32(static_cast<uint32_t>(f.size()));
  for (size_t i = 0; i < f.size(); ++i) {
    const Keypoint& p = f.keypoints[i];
    w.f32(p.u);
    w.f32(p.v);
    w.f32(p.angle_deg);
    w.f32(p.response);
    w.i32(p.octave);
    writeDescriptor(w, f.descriptors[i]);
    w.f32(f.right_u[i]);
    w.f32(f.depth[i]);
  }
}

void encodeKeyframe(ByteWriter& w, const KeyframeSnapshot& k, uint32_t chunk) {
  w.i64(k.id);
  w.u64(k.frame_id);
  w.i64(k.timestamp_ns);
  writePose(w, k.T_C_G);
  w.u8((k.bad ? kBadFlag : 0) | (k.first_connection_pending ? kFirstConnectionPendingFlag : 0));
  w.i64(k.parent);
  writePose(w, k.T_parent_this);
  w.u32(static_cast<uint32_t>(k.connections.size()));
  for (const auto& [other, weight] : k.connections) {
    w.i64(other);
    w.i32(weight);
  }
  w.u32(static_cast<uint32_t>(k.loop_edges.size()));
  for (const KeyframeId other : k.loop_edges) w.i64(other);
  w.u32(chunk);
}

bool decodeKeyframe(ByteReader& r, KeyframeSnapshot* k, uint32_t* chunk, std::string* error) {
  uint8_t flags = 0;
  r.i64(&k->id);
  r.u64(&k->frame_id);
  r.i64(&k->timestamp_ns);
  if (!readPose(r, &k->T_C_G)) return (*error = "T_C_G truncated or not a pose", false);
  r.u8(&flags);
  r.i64(&k->parent);
  if (!readPose(r, &k->T_parent_this)) {
    return (*error = "T_parent_this truncated or not a pose", false);
  }
  if (flags & ~(kBadFlag | kFirstConnectionPendingFlag)) {
    return (*error = "unknown flags " + std::to_string(flags), false);
  }
  k->bad = (flags & kBadFlag) != 0;
  k->first_connection_pending = (flags & kFirstConnectionPendingFlag) != 0;
  uint64_t n = 0;
  if (!readCount(r, kConnectionBytes, &n, "connection", error)) return false;
  k->connections.resize(n);
  for (auto& [other, weight] : k->connections) {
    r.i64(&other);
    r.i32(&weight);
  }
  if (!readCount(r, kLoopEdgeBytes, &n, "loop edge", error)) return false;
  k->loop_edges.resize(n);
  for (KeyframeId& other : k->loop_edges) r.i64(&other);
  if (!r.u32(chunk)) return (*error = "truncated", false);
  return true;
}

void encodeLandmark(ByteWriter& w, const LandmarkSnapshot& l) {
  w.u64(l.id);
  for (const double v : {l.p_G.x(), l.p_G.y(), l.p_G.z(), l.normal.x(), l.normal.y(),
                         l.normal.z(), l.min_distance, l.max_distance}) {
    w.f64(v);
  }
  writeDescriptor(w, l.descriptor);
  w.i64(l.reference);
  w.i64(l.first_keyframe_id);
  w.i32(l.visible);
  w.i32(l.found);
  w.u32(static_cast<uint32_t>(l.observations.size()));
  for (const auto& [keyframe, index] : l.observations) {
    w.i64(keyframe);
    w.u32(index);
  }
}

bool decodeLandmark(ByteReader& r, LandmarkSnapshot* l, std::string* error) {
  r.u64(&l->id);
  for (double* v : {&l->p_G.x(), &l->p_G.y(), &l->p_G.z(), &l->normal.x(), &l->normal.y(),
                    &l->normal.z(), &l->min_distance, &l->max_distance}) {
    r.f64(v);
  }
  readDescriptor(r, &l->descriptor);
  r.i64(&l->reference);
  r.i64(&l->first_keyframe_id);
  r.i32(&l->visible);
  r.i32(&l->found);
  uint64_t n = 0;
  if (!readCount(r, kObservationBytes, &n, "observation", error)) return false;
  l->observations.resize(n);
  for (auto& [keyframe, index] : l->observations) {
    r.i64(&keyframe);
    r.u32(&index);
  }
  return r.ok() || (*error = "truncated", false);
}

}  // namespace

std::string keyframeChunkFileName(int32_t map_epoch, uint64_t generation) {
  return "keyframes_e" + std::to_string(map_epoch) + "_g" + std::to_string(generation) + ".cbkf";
}

namespace {

// The index's raw section (before compression).
std::string encodeIndexSection(const TrackerMapIndex& index) {
  const TrackerMapState& s = index.state;
  std::string raw;
  ByteWriter w(&raw);
  w.u64(s.generation);
  w.i32(s.map_epoch);
  const PinholeIntrinsics& k = s.camera.intrinsics;
  for (const double v : {k.fx, k.fy, k.cx, k.cy, s.camera.baseline_m}) w.f64(v);
  w.i32(k.width);
  w.i32(k.height);
  w.u64(s.map.next_landmark_id);
  w.i32(s.map.change_index);
  w.u32(static_cast<uint32_t>(index.chunks.size()));
  for (const KeyframeChunkRef& c : index.chunks) {
    w.str(c.file_name);
    w.u64(c.file_size);
    w.u64(c.payload_xxh64);
  }
  w.u32(static_cast<uint32_t>(s.map.keyframes.size()));
  for (size_t i = 0; i < s.map.keyframes.size(); ++i) {
    encodeKeyframe(w, s.map.keyframes[i], index.keyframe_chunk[i]);
  }
  w.u32(static_cast<uint32_t>(s.map.landmarks.size()));
  for (const LandmarkSnapshot& l : s.map.landmarks) encodeLandmark(w, l);
  return raw;
}

}  // namespace

std::string encodeTrackerMapIndex(const TrackerMapIndex& index) {
  std::string payload;
  appendZstdBlob(encodeIndexSection(index), kZstdLevel, &payload);
  return payload;
}

uint64_t keyframeFeaturesDigest(const KeyframeSnapshot& keyframe) {
  std::string raw;
  ByteWriter w(&raw);
  w.u64(keyframe.frame_id);
  w.i64(keyframe.timestamp_ns);
  encodeFeatures(w, keyframe);
  return mapFileChecksum(raw);
}

uint64_t keyframeStateDigest(const KeyframeSnapshot& keyframe) {
  std::string raw;
  ByteWriter w(&raw);
  encodeKeyframe(w, keyframe, 0);
  return mapFileChecksum(raw);
}

uint64_t landmarksDigest(const SparseMapSnapshot& map) {
  std::string raw;
  ByteWriter w(&raw);
  w.i32(map.change_index);
  for (const LandmarkSnapshot& l : map.landmarks) encodeLandmark(w, l);
  return mapFileChecksum(raw);
}

std::optional<TrackerMapIndex> decodeTrackerMapIndex(std::string_view payload,
                                                     std::string* error) {
  std::string raw;
  std::string problem = readZstdBlob(payload, &raw);
  if (!problem.empty()) return failed<TrackerMapIndex>(error, problem);
  ByteReader r(raw);
  TrackerMapIndex index;
  TrackerMapState& s = index.state;
  r.u64(&s.generation);
  r.i32(&s.map_epoch);
  PinholeIntrinsics& k = s.camera.intrinsics;
  for (double* v : {&k.fx, &k.fy, &k.cx, &k.cy, &s.camera.baseline_m}) r.f64(v);
  r.i32(&k.width);
  r.i32(&k.height);
  r.u64(&s.map.next_landmark_id);
  r.i32(&s.map.change_index);
  if (!r.ok()) return failed<TrackerMapIndex>(error, "truncated in the header fields");
  if (s.map_epoch < 0) return failed<TrackerMapIndex>(error, "negative map epoch");
  if (!validate(k).empty() || !std::isfinite(s.camera.baseline_m) || s.camera.baseline_m <= 0) {
    return failed<TrackerMapIndex>(error, "invalid camera");
  }
  uint64_t n = 0;
  if (!readCount(r, kMinChunkRefBytes, &n, "chunk", &problem)) {
    return failed<TrackerMapIndex>(error, problem);
  }
  index.chunks.resize(n);
  std::set<std::string> names;
  for (KeyframeChunkRef& c : index.chunks) {
    if (!r.str(&c.file_name, kMaxFileNameBytes)) {
      return failed<TrackerMapIndex>(error, "chunk file name truncated or too long");
    }
    r.u64(&c.file_size);
    r.u64(&c.payload_xxh64);
    if (c.file_name.empty() || c.file_name.find('/') != std::string::npos ||
        c.file_name.front() == '.' || !names.insert(c.file_name).second) {
      return failed<TrackerMapIndex>(error, "bad or repeated chunk file name '" + c.file_name + "'");
    }
  }
  if (!readCount(r, kMinKeyframeBytes, &n, "keyframe", &problem)) {
    return failed<TrackerMapIndex>(error, problem);
  }
  s.map.keyframes.resize(n);
  index.keyframe_chunk.resize(n);
  for (size_t i = 0; i < n; ++i) {
    KeyframeSnapshot& kf = s.map.keyframes[i];
    if (!decodeKeyframe(r, &kf, &index.keyframe_chunk[i], &problem)) {
      return failed<TrackerMapIndex>(error, "keyframe " + std::to_string(i) + ": " + problem);
    }
    const uint32_t chunk = index.keyframe_chunk[i];
    if (kf.bad != (chunk == kNoKeyframeChunk) ||
        (chunk != kNoKeyframeChunk && chunk >= index.chunks.size())) {
      return failed<TrackerMapIndex>(error, "keyframe " + std::to_string(i) + ": chunk " +
                                                std::to_string(chunk) + " out of range");
    }
  }
  if (!readCount(r, kMinLandmarkBytes, &n, "landmark", &problem)) {
    return failed<TrackerMapIndex>(error, problem);
  }
  s.map.landmarks.resize(n);
  for (size_t i = 0; i < n; ++i) {
    if (!decodeLandmark(r, &s.map.landmarks[i], &problem)) {
      return failed<TrackerMapIndex>(error, "landmark #" + std::to_string(i) + ": " + problem);
    }
  }
  if (r.remaining() != 0) {
    return failed<TrackerMapIndex>(error, std::to_string(r.remaining()) + " bytes left over");
  }
  return index;
}

std::string encodeKeyframeChunk(const std::vector<const KeyframeSnapshot*>& keyframes) {
  std::string raw;
  ByteWriter w(&raw);
  w.u32(static_cast<uint32_t>(keyframes.size()));
  for (const KeyframeSnapshot* k : keyframes) encodeFeatures(w, *k);
  std::string payload;
  appendZstdBlob(raw, kZstdLevel, &payload);
  return payload;
}

std::optional<std::map<KeyframeId, std::shared_ptr<FrameFeatures>>> decodeKeyframeChunk(
    std::string_view payload, std::string* error) {
  using Result = std::map<KeyframeId, std::shared_ptr<FrameFeatures>>;
  std::string raw;
  std::string problem = readZstdBlob(payload, &raw);
  if (!problem.empty()) return failed<Result>(error, problem);
  ByteReader r(raw);
  uint64_t num_keyframes = 0, num_features = 0;
  if (!readCount(r, kMinChunkKeyframeBytes, &num_keyframes, "keyframe", &problem)) {
    return failed<Result>(error, problem);
  }
  Result result;
  for (uint64_t j = 0; j < num_keyframes; ++j) {
    KeyframeId id = 0;
    r.i64(&id);
    if (!readCount(r, kFeatureBytes, &num_features, "feature", &problem)) {
      return failed<Result>(error, "keyframe #" + std::to_string(j) + ": " + problem);
    }
    auto f = std::make_shared<FrameFeatures>();
    f->keypoints.resize(num_features);
    f->descriptors.resize(num_features);
    f->right_u.resize(num_features);
    f->depth.resize(num_features);
    for (size_t i = 0; i < num_features; ++i) {
      Keypoint& p = f->keypoints[i];
      r.f32(&p.u);
      r.f32(&p.v);
      r.f32(&p.angle_deg);
      r.f32(&p.response);
      r.i32(&p.octave);
      readDescriptor(r, &f->descriptors[i]);
      r.f32(&f->right_u[i]);
      r.f32(&f->depth[i]);
    }
    if (!result.emplace(id, std::move(f)).second) {
      return failed<Result>(error, "keyframe " + std::to_string(id) + " appears twice");
    }
  }
  if (!r.ok()) return failed<Result>(error, "truncated");
  if (r.remaining() != 0) {
    return failed<Result>(error, std::to_string(r.remaining()) + " bytes left over");
  }
  return result;
}

bool hasTrackerMap(const std::string& dir) {
  std::error_code ec;
  return std::filesystem::exists(std::filesystem::path(dir) / kTrackerMapFileName, ec);
}

std::optional<TrackerMapState> loadTrackerMap(const std::string& dir, std::string* error,
                                              TrackerMapIndex* index_out) {
  const std::string index_path = (std::filesystem::path(dir) / kTrackerMapFileName).string();
  std::string problem;
  const std::optional<MapFile> file =
      readMapFile(index_path, kTrackerMapMagic, kTrackerMapVersion, "tracker map", &problem);
  if (!file) return failed<TrackerMapState>(error, problem);
  std::optional<TrackerMapIndex> index = decodeTrackerMapIndex(file->payload, &problem);
  if (!index) return failed<TrackerMapState>(error, index_path + ": " + problem);

  std::vector<std::map<KeyframeId, std::shared_ptr<FrameFeatures>>> chunks;
  for (const KeyframeChunkRef& ref : index->chunks) {
    const std::string path = (std::filesystem::path(dir) / ref.file_name).string();
    const std::optional<MapFile> chunk = readMapFile(path, kKeyframeChunkMagic, kTrackerMapVersion,
                                                     "keyframe features file", &problem);
    if (!chunk) return failed<TrackerMapState>(error, problem);
    if (chunk->file_size != ref.file_size || chunk->payload_xxh64 != ref.payload_xxh64) {
      return failed<TrackerMapState>(
          error, path + ": not the file the tracker map lists (size or checksum differs)");
    }
    auto features = decodeKeyframeChunk(chunk->payload, &problem);
    if (!features) return failed<TrackerMapState>(error, path + ": " + problem);
    chunks.push_back(std::move(*features));
  }
  TrackerMapState state = std::move(index->state);
  for (size_t i = 0; i < state.map.keyframes.size(); ++i) {
    KeyframeSnapshot& k = state.map.keyframes[i];
    const uint32_t c = index->keyframe_chunk[i];
    if (c == kNoKeyframeChunk) {
      k.features = emptyFrameFeatures();
      continue;
    }
    const auto it = chunks[c].find(k.id);
    if (it == chunks[c].end()) {
      return failed<TrackerMapState>(error, index_path + ": keyframe " + std::to_string(k.id) +
                                                " is not in " + index->chunks[c].file_name);
    }
    k.features = it->second;
  }
  problem = state.map.validate(std::numeric_limits<int>::max());
  if (!problem.empty()) return failed<TrackerMapState>(error, index_path + ": " + problem);
  if (index_out != nullptr) {
    index_out->state.generation = state.generation;
    index_out->state.map_epoch = state.map_epoch;
    index_out->state.camera = state.camera;
    index_out->chunks = std::move(index->chunks);
    index_out->keyframe_chunk = std::move(index->keyframe_chunk);
  }
  return state;
}

}  // namespace cblox
