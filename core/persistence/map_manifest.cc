#include "core/persistence/map_manifest.h"

#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <utility>

#include "core/io/atomic_file.h"
#include "core/persistence/byte_codec.h"
#include "core/persistence/pose_codec.h"
#include "core/persistence/map_file_header.h"

namespace cblox {
namespace {

using persistence_detail::ByteReader;
using persistence_detail::ByteWriter;
using persistence_detail::readPose;
using persistence_detail::writePose;

constexpr size_t kMaxCounterNameBytes = 256;
constexpr size_t kMaxFileNameBytes = 256;
// Smallest encodings, for bounding counts by the bytes that remain.
constexpr size_t kMinSubmapRecordBytes = 3 * 8 + 7 * 8 + 1 + 4 + 4 + 8 + 8 + 8;
constexpr size_t kMinCounterBytes = 4 + 8;
constexpr size_t kMinLandmarkSetBytes = 8 + 4;       // a subvolume record
constexpr size_t kMinKeyframeLandmarksBytes = 8 + 4;  // a keyframe's set
constexpr size_t kBackoffBytes = 8 + 8 + 4 + 8;

std::string manifestPath(const std::string& dir) {
  return (std::filesystem::path(dir) / kManifestFileName).string();
}

std::optional<MapManifest> fail(std::string* error, const std::string& path,
                                const std::string& what) {
  if (error != nullptr) *error = path + ": " + what;
  return std::nullopt;
}

void encodeLandmarkIds(const std::vector<uint64_t>& ids, ByteWriter* w) {
  w->u32(static_cast<uint32_t>(ids.size()));
  uint64_t previous = 0;
  for (size_t k = 0; k < ids.size(); ++k) {
    w->uvarint(k == 0 ? ids[k] : ids[k] - previous);
    previous = ids[k];
  }
}

// The version 3 maintenance section (map_manifest.h).
void encodeMaintenance(const FusionSchedulerState& state, ByteWriter* w) {
  w->u32(static_cast<uint32_t>(state.subvolumes.size()));
  for (const SubvolumeLandmarks& s : state.subvolumes) {
    w->i64(s.subvolume);
    w->u32(static_cast<uint32_t>(s.keyframes.size()));
    for (const KeyframeLandmarks& k : s.keyframes) {
      w->i64(k.keyframe);
      encodeLandmarkIds(k.landmark_ids, w);
    }
  }
  w->u32(static_cast<uint32_t>(state.backoffs.size()));
  for (const FusionPairBackoff& b : state.backoffs) {
    w->i64(b.older);
    w->i64(b.newer);
    w->i32(b.rejections);
    w->f64(b.retry_in_s);
  }
}

std::string outOfBounds(const ByteReader& r, const std::string& what, uint64_t n) {
  return what + " " + std::to_string(n) + " out of bounds for the " +
         std::to_string(r.remaining()) + " bytes that remain";
}

// Reads a landmark id set (count, then ascending uvarint differences); empty when fine.
std::string decodeLandmarkIds(ByteReader* r, const std::string& at, std::vector<uint64_t>* ids) {
  uint32_t num_landmarks = 0;
  if (!r->u32(&num_landmarks)) return "truncated: the payload ends inside " + at;
  if (num_landmarks > r->remaining()) {  // at least one byte each
    return at + ": " + outOfBounds(*r, "landmark count", num_landmarks);
  }
  ids->resize(num_landmarks);
  uint64_t previous = 0;
  for (size_t k = 0; k < num_landmarks; ++k) {
    uint64_t v = 0;
    if (!r->uvarint(&v)) return at + ": truncated or malformed landmark id " + std::to_string(k);
    if (k > 0 && (v == 0 || v > UINT64_MAX - previous)) {
      return at + ": landmark id " + std::to_string(k) + " does not increase (difference " +
             std::to_string(v) + ")";
    }
    previous = (*ids)[k] = k == 0 ? v : previous + v;
  }
  return "";
}

// Reads the maintenance section of a version 2 or 3 manifest into *state; empty when fine,
// else what is wrong. Version 2 kept one landmark set per subvolume: it is read as the set of
// a keyframe not known (KeyframeLandmarks::kUnknownKeyframe). Every count is bounded by the
// bytes that remain before anything is allocated.
std::string decodeMaintenance(ByteReader* r, uint32_t version, FusionSchedulerState* state) {
  uint32_t num_subvolumes = 0;
  if (!r->u32(&num_subvolumes)) return "truncated: the payload ends inside the maintenance count";
  if (num_subvolumes > r->remaining() / kMinLandmarkSetBytes) {
    return outOfBounds(*r, "maintenance subvolume count", num_subvolumes);
  }
  state->subvolumes.resize(num_subvolumes);
  for (SubvolumeLandmarks& s : state->subvolumes) {
    const std::string at = "maintenance record " + std::to_string(&s - state->subvolumes.data());
    if (!r->i64(&s.subvolume)) return "truncated: the payload ends inside " + at;
    if (version == 2) {
      s.keyframes.resize(1);
      s.keyframes[0].keyframe = KeyframeLandmarks::kUnknownKeyframe;
      if (std::string e = decodeLandmarkIds(r, at, &s.keyframes[0].landmark_ids); !e.empty()) {
        return e;
      }
      continue;
    }
    uint32_t num_keyframes = 0;
    if (!r->u32(&num_keyframes)) return "truncated: the payload ends inside " + at;
    if (num_keyframes > r->remaining() / kMinKeyframeLandmarksBytes) {
      return at + ": " + outOfBounds(*r, "keyframe count", num_keyframes);
    }
    s.keyframes.resize(num_keyframes);
    for (KeyframeLandmarks& k : s.keyframes) {
      const std::string in = at + " keyframe " + std::to_string(&k - s.keyframes.data());
      if (!r->i64(&k.keyframe)) return "truncated: the payload ends inside " + in;
      if (std::string e = decodeLandmarkIds(r, in, &k.landmark_ids); !e.empty()) return e;
    }
  }
  uint32_t num_backoffs = 0;
  if (!r->u32(&num_backoffs)) return "truncated: the payload ends inside the back-off count";
  if (num_backoffs > r->remaining() / kBackoffBytes) {
    return outOfBounds(*r, "back-off count", num_backoffs);
  }
  state->backoffs.resize(num_backoffs);
  for (FusionPairBackoff& b : state->backoffs) {
    r->i64(&b.older);
    r->i64(&b.newer);
    r->i32(&b.rejections);
    r->f64(&b.retry_in_s);
  }
  if (!r->ok()) return "truncated: the payload ends inside the back-offs";
  return "";
}

}  // namespace

std::string MapManifest::validate() const {
  if (const std::string e = config.validate(); !e.empty()) return "config: " + e;
  std::optional<SubmapId> unfinished;
  for (size_t i = 0; i < submaps.size(); ++i) {
    const SubmapRecord& s = submaps[i];
    const std::string at = "submap " + std::to_string(s.id) + ": ";
    if (i > 0 && s.id <= submaps[i - 1].id) return at + "ids do not strictly increase";
    if (s.id < 0 || s.id >= next_submap_id) {
      return at + "id is not in [0, next submap id " + std::to_string(next_submap_id) + ")";
    }
    if (!isFinitePose(s.T_G_M)) return at + "T_G_M is not finite";
    for (size_t k = 1; k < s.keyframe_ids.size(); ++k) {
      if (s.keyframe_ids[k] <= s.keyframe_ids[k - 1]) return at + "keyframe ids not ascending";
    }
    if (!std::binary_search(s.keyframe_ids.begin(), s.keyframe_ids.end(), s.anchor_keyframe)) {
      return at + "keyframe ids lack the anchor keyframe";
    }
    SubmapId file_id = 0;
    uint64_t file_generation = 0;
    if (!parseSubmapFileName(s.file.file_name, &file_id, &file_generation) || file_id != s.id ||
        file_generation > generation) {
      return at + "file name \"" + s.file.file_name + "\" is not submap_" + std::to_string(s.id) +
             "_g<generation <= " + std::to_string(generation) + ">.cbsub";
    }
    if (!s.finished) {
      if (unfinished) return at + "more than one unfinished submap";
      unfinished = s.id;
    }
  }
  if (active_submap_id != unfinished) {
    return active_submap_id
               ? "the active submap " + std::to_string(*active_submap_id) +
                     " is not the one unfinished submap listed"
               : "submap " + std::to_string(*unfinished) + " is unfinished but no submap is active";
  }
  for (const auto& [name, value] : counters) {
    if (name.empty() || name.size() > kMaxCounterNameBytes) {
      return "counter name \"" + name.substr(0, 32) + "\" is empty or longer than " +
             std::to_string(kMaxCounterNameBytes) + " bytes";
    }
  }
  if (const std::string e = maintenance.validate(); !e.empty()) return "maintenance: " + e;
  const auto listed = [this](int64_t id) {  // the ids strictly increase (checked above)
    const auto it = std::lower_bound(submaps.begin(), submaps.end(), id,
                                     [](const SubmapRecord& s, int64_t v) { return s.id < v; });
    return it != submaps.end() && it->id == id;
  };
  for (const SubvolumeLandmarks& s : maintenance.subvolumes) {
    if (!listed(s.subvolume)) {
      return "maintenance: subvolume " + std::to_string(s.subvolume) + " is not a listed submap";
    }
  }
  for (const FusionPairBackoff& b : maintenance.backoffs) {
    if (!listed(b.older) || !listed(b.newer)) {
      return "maintenance: back-off of pair (" + std::to_string(b.older) + ", " +
             std::to_string(b.newer) + ") names a submap that is not listed";
    }
  }
  return "";
}

std::string encodeManifest(const MapManifest& manifest) {
  std::string payload;
  ByteWriter w(&payload);
  w.u64(manifest.generation);
  w.f32(manifest.config.layer.voxel_size);
  w.i32(manifest.config.layer.voxels_per_side);
  w.i64(manifest.next_submap_id);
  w.u8(manifest.active_submap_id ? 1 : 0);
  w.i64(manifest.active_submap_id.value_or(0));
  w.u32(static_cast<uint32_t>(manifest.submaps.size()));
  for (const SubmapRecord& s : manifest.submaps) {
    w.i64(s.id);
    w.i64(s.anchor_keyframe);
    w.i64(s.creation_time_ns);
    writePose(w, s.T_G_M);
    w.u8(s.finished ? 1 : 0);
    w.u32(static_cast<uint32_t>(s.keyframe_ids.size()));
    for (const KeyframeId k : s.keyframe_ids) w.i64(k);
    w.str(s.file.file_name);
    w.u64(s.file.file_size);
    w.u64(s.file.payload_xxh64);
    w.u64(s.file.num_blocks);
  }
  w.u32(static_cast<uint32_t>(manifest.counters.size()));
  for (const auto& [name, value] : manifest.counters) {
    w.str(name);
    w.i64(value);
  }
  encodeMaintenance(manifest.maintenance, &w);
  return sealMapFile(kManifestFileMagic, kManifestVersion, payload);
}

bool writeManifest(const MapManifest& manifest, const std::string& dir, std::string* error) {
  const std::string path = manifestPath(dir);
  if (const std::string e = manifest.validate(); !e.empty()) {
    if (error != nullptr) *error = path + ": not written, the manifest is inconsistent: " + e;
    return false;
  }
  return writeFileAtomically(path, encodeManifest(manifest), error);
}

std::optional<MapManifest> readManifest(const std::string& dir, std::string* error) {
  const std::string path = manifestPath(dir);
  const std::optional<MapFile> file =
      readMapFile(path, kManifestFileMagic, kManifestVersion, "map manifest", error);
  if (!file) return std::nullopt;
  ByteReader r(file->payload);
  const auto truncated = [&](const std::string& where) {
    return fail(error, path, "truncated: the payload ends inside " + where);
  };
  MapManifest m;
  uint8_t has_active = 0;
  int64_t active_id = 0;
  uint32_t num_submaps = 0;
  r.u64(&m.generation);
  r.f32(&m.config.layer.voxel_size);
  r.i32(&m.config.layer.voxels_per_side);
  r.i64(&m.next_submap_id);
  r.u8(&has_active);
  r.i64(&active_id);
  r.u32(&num_submaps);
  if (!r.ok()) return truncated("the collection header");
  if (has_active > 1) return fail(error, path, "invalid active flag " + std::to_string(has_active));
  if (has_active == 1) m.active_submap_id = active_id;
  if (num_submaps > r.remaining() / kMinSubmapRecordBytes) {
    return fail(error, path,
                "submap count " + std::to_string(num_submaps) + " out of bounds for the " +
                    std::to_string(r.remaining()) + " bytes that remain");
  }
  m.submaps.resize(num_submaps);
  for (SubmapRecord& s : m.submaps) {
    const std::string at = "submap record " + std::to_string(&s - m.submaps.data());
    uint8_t finished = 0;
    uint32_t num_keyframes = 0;
    r.i64(&s.id);
    r.i64(&s.anchor_keyframe);
    r.i64(&s.creation_time_ns);
    const bool pose_ok = readPose(r, &s.T_G_M);
    r.u8(&finished);
    r.u32(&num_keyframes);
    if (!r.ok()) return truncated(at);
    if (!pose_ok) return fail(error, path, at + ": T_G_M is not finite or its quaternion not unit");
    if (finished > 1) return fail(error, path, at + ": invalid finished flag");
    s.finished = finished == 1;
    if (num_keyframes > r.remaining() / 8) {
      return fail(error, path,
                  at + ": keyframe count " + std::to_string(num_keyframes) +
                      " out of bounds for the " + std::to_string(r.remaining()) +
                      " bytes that remain");
    }
    s.keyframe_ids.resize(num_keyframes);
    for (KeyframeId& k : s.keyframe_ids) r.i64(&k);
    if (!r.str(&s.file.file_name, kMaxFileNameBytes)) {
      return fail(error, path,
                  at + ": file name length out of bounds (truncated or longer than " +
                      std::to_string(kMaxFileNameBytes) + " bytes)");
    }
    r.u64(&s.file.file_size);
    r.u64(&s.file.payload_xxh64);
    r.u64(&s.file.num_blocks);
    if (!r.ok()) return truncated(at);
  }
  uint32_t num_counters = 0;
  if (!r.u32(&num_counters)) return truncated("the counter count");
  if (num_counters > r.remaining() / kMinCounterBytes) {
    return fail(error, path,
                "counter count " + std::to_string(num_counters) + " out of bounds for the " +
                    std::to_string(r.remaining()) + " bytes that remain");
  }
  for (uint32_t i = 0; i < num_counters; ++i) {
    std::string name;
    int64_t value = 0;
    if (!r.str(&name, kMaxCounterNameBytes) || !r.i64(&value)) {
      return fail(error, path,
                  "counter " + std::to_string(i) + ": truncated or name longer than " +
                      std::to_string(kMaxCounterNameBytes) + " bytes");
    }
    if (!m.counters.emplace(std::move(name), value).second) {
      return fail(error, path, "counter " + std::to_string(i) + " repeats a name");
    }
  }
  if (file->version >= 2) {
    if (const std::string e = decodeMaintenance(&r, file->version, &m.maintenance); !e.empty()) {
      return fail(error, path, e);
    }
  }
  if (r.remaining() != 0) {
    return fail(error, path,
                std::to_string(r.remaining()) + " unexpected bytes after the " +
                    (file->version >= 2 ? "maintenance section" : "counters"));
  }
  if (const std::string e = m.validate(); !e.empty())
    return fail(error, path, "inconsistent: " + e);
  return m;
}

}  // namespace cblox
