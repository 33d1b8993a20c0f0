#include "core/persistence/tracker_map_checkpointer.h"

#include <chrono>
#include <filesystem>
#include <set>
#include <stdexcept>
#include <thread>

#include <unistd.h>

#include "core/io/atomic_file.h"
#include "core/persistence/id_lease.h"
#include "core/persistence/map_file_header.h"

namespace cblox {

namespace fs = std::filesystem;

namespace {

// The generation G of "keyframes_e<E>_g<G>.cbkf", or nullopt for any other name.
std::optional<uint64_t> chunkGeneration(const std::string& name) {
  if (name.rfind("keyframes_e", 0) != 0 || name.size() < 5 ||
      name.substr(name.size() - 5) != ".cbkf") {
    return std::nullopt;
  }
  const size_t g = name.rfind("_g");
  if (g == std::string::npos) return std::nullopt;
  try {
    size_t used = 0;
    const std::string digits = name.substr(g + 2, name.size() - 5 - (g + 2));
    const uint64_t generation = std::stoull(digits, &used);
    return used == digits.size() ? std::optional<uint64_t>(generation) : std::nullopt;
  } catch (const std::exception&) {
    return std::nullopt;
  }
}

}  // namespace

TrackerMapCheckpointer::TrackerMapCheckpointer(std::string dir) : dir_(std::move(dir)) {}

void TrackerMapCheckpointer::adoptLoaded(const TrackerMapIndex& index) {
  generation_ = index.state.generation;
  map_epoch_ = index.state.map_epoch;
  chunks_ = index.chunks;
  chunk_of_.clear();
  for (size_t i = 0; i < index.keyframe_chunk.size(); ++i) {
    if (index.keyframe_chunk[i] != kNoKeyframeChunk) {
      chunk_of_[static_cast<KeyframeId>(i)] = index.keyframe_chunk[i];
    }
  }
}

uint64_t TrackerMapCheckpointer::nextGeneration() const {
  uint64_t newest = generation_;
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(dir_, ec)) {
    if (const auto g = chunkGeneration(entry.path().filename().string())) {
      newest = std::max(newest, *g);
    }
  }
  return newest + 1;
}

void TrackerMapCheckpointer::deleteUnlistedChunks(const std::vector<KeyframeChunkRef>& listed) const {
  std::set<std::string> keep;
  for (const KeyframeChunkRef& c : listed) keep.insert(c.file_name);
  // Temporary files left by a crash (writeFileAtomically's "<name>.tmp.<pid>.<n>"): those of
  // the index and chunks (this is their only writer), and leases of other processes (the
  // tracking thread may be writing this one's right now).
  const std::string own_lease_tmp =
      std::string(kIdLeaseFileName) + ".tmp." + std::to_string(::getpid()) + ".";
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(dir_, ec)) {
    const std::string name = entry.path().filename().string();
    const bool leftover =
        name.find(".tmp.") != std::string::npos &&
        (name.rfind(kTrackerMapFileName, 0) == 0 || name.rfind("keyframes_e", 0) == 0 ||
         (name.rfind(kIdLeaseFileName, 0) == 0 && name.rfind(own_lease_tmp, 0) != 0));
    if (leftover || (chunkGeneration(name) && keep.count(name) == 0)) fs::remove(entry.path(), ec);
  }
}

std::optional<TrackerCheckpointReport> TrackerMapCheckpointer::checkpoint(
    const TrackerMapState& state, std::string* error) {
  const auto start = std::chrono::steady_clock::now();
  std::error_code ec;
  fs::create_directories(dir_, ec);
  if (ec) {
    if (error != nullptr) *error = dir_ + ": cannot create the directory: " + ec.message();
    return std::nullopt;
  }
  const bool same_map = state.map_epoch == map_epoch_;
  const uint64_t generation = nextGeneration();
  TrackerCheckpointReport report;
  report.generation = generation;

  // The features of keyframes no chunk holds yet go into this generation's chunk.
  std::vector<const KeyframeSnapshot*> fresh;
  for (const KeyframeSnapshot& k : state.map.keyframes) {
    if (!k.bad && (!same_map || chunk_of_.count(k.id) == 0)) fresh.push_back(&k);
  }
  std::vector<KeyframeChunkRef> chunks = same_map ? chunks_ : std::vector<KeyframeChunkRef>{};
  std::map<KeyframeId, size_t> chunk_of = same_map ? chunk_of_ : std::map<KeyframeId, size_t>{};
  if (!fresh.empty()) {
    KeyframeChunkRef ref;
    ref.file_name = keyframeChunkFileName(state.map_epoch, generation);
    const std::string payload = encodeKeyframeChunk(fresh);
    const std::string bytes = sealMapFile(kKeyframeChunkMagic, kTrackerMapVersion, payload);
    std::this_thread::sleep_for(pause_);
    if (!writeFileAtomically((fs::path(dir_) / ref.file_name).string(), bytes, error)) {
      return std::nullopt;
    }
    ref.file_size = bytes.size();
    ref.payload_xxh64 = mapFileChecksum(payload);
    for (const KeyframeSnapshot* k : fresh) chunk_of[k->id] = chunks.size();
    chunks.push_back(ref);
    report.keyframes_written = fresh.size();
    report.bytes_written += bytes.size();
  }

  // The index lists only the chunks still holding a good keyframe, renumbered.
  TrackerMapIndex index;
  index.state.generation = generation;
  index.state.map_epoch = state.map_epoch;
  index.state.camera = state.camera;
  index.state.map.next_landmark_id = state.map.next_landmark_id;
  index.state.map.change_index = state.map.change_index;
  index.state.map.landmarks = state.map.landmarks;
  std::vector<uint32_t> renumbered(chunks.size(), kNoKeyframeChunk);
  for (const KeyframeSnapshot& k : state.map.keyframes) {
    KeyframeSnapshot copy = k;
    copy.features = nullptr;
    index.state.map.keyframes.push_back(std::move(copy));
    if (k.bad) {
      index.keyframe_chunk.push_back(kNoKeyframeChunk);
      continue;
    }
    const size_t c = chunk_of.at(k.id);
    if (renumbered[c] == kNoKeyframeChunk) {
      renumbered[c] = static_cast<uint32_t>(index.chunks.size());
      index.chunks.push_back(chunks[c]);
    }
    index.keyframe_chunk.push_back(renumbered[c]);
  }
  const std::string payload = encodeTrackerMapIndex(index);
  const std::string bytes = sealMapFile(kTrackerMapMagic, kTrackerMapVersion, payload);
  std::this_thread::sleep_for(pause_);
  if (!writeFileAtomically((fs::path(dir_) / kTrackerMapFileName).string(), bytes, error)) {
    return std::nullopt;
  }
  report.bytes_written += bytes.size();
  deleteUnlistedChunks(index.chunks);

  adoptLoaded(index);
  report.keyframes = index.state.map.keyframes.size();
  report.landmarks = index.state.map.landmarks.size();
  report.milliseconds =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  return report;
}

}  // namespace cblox
