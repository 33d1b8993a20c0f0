#include "core/persistence/map_store.h"

#include <algorithm>
#include <filesystem>
#include <system_error>
#include <thread>
#include <unordered_map>
#include <unordered_set>
#include <utility>

#include "core/io/atomic_file.h"
#include "core/persistence/map_file_header.h"

namespace cblox {
namespace {

namespace fs = std::filesystem;

bool setError(std::string* error, std::string message) {
  if (error != nullptr) *error = std::move(message);
  return false;
}

// Creates `dir` when missing and makes its entry durable.
bool ensureDirectory(const std::string& dir, std::string* error) {
  std::error_code ec;
  if (fs::is_directory(dir, ec)) return true;
  if (!fs::create_directories(dir, ec) && ec) {
    return setError(error, dir + ": cannot create the map directory: " + ec.message());
  }
  const fs::path parent = fs::absolute(fs::path(dir), ec).parent_path();
  return syncDirectory(parent.empty() ? std::string(".") : parent.string(), error);
}

// The highest generation any submap file in `dir` or its manifest carries (0 when none).
uint64_t highestGeneration(const std::string& dir) {
  uint64_t highest = 0;
  std::error_code ec;
  for (const fs::directory_entry& entry : fs::directory_iterator(dir, ec)) {
    uint64_t generation = 0;
    if (parseSubmapFileName(entry.path().filename().string(), nullptr, &generation)) {
      highest = std::max(highest, generation);
    }
  }
  if (const std::optional<MapManifest> manifest = readManifest(dir, nullptr)) {
    highest = std::max(highest, manifest->generation);
  }
  return highest;
}

// `state` without the subvolumes and pairs that the snapshot does not list (created after it,
// or fused away before it).
FusionSchedulerState restrictedTo(FusionSchedulerState state, const SubmapCollectionState& map) {
  std::unordered_set<SubmapId> ids;
  for (const std::shared_ptr<Submap>& submap : map.submaps) ids.insert(submap->id());
  std::erase_if(state.subvolumes,
                [&](const SubvolumeLandmarks& s) { return !ids.contains(s.subvolume); });
  std::erase_if(state.backoffs, [&](const FusionPairBackoff& b) {
    return !ids.contains(b.older) || !ids.contains(b.newer);
  });
  return state;
}

bool sameGeometry(const LayerConfig& a, const LayerConfig& b) {
  return a.voxel_size == b.voxel_size && a.voxels_per_side == b.voxels_per_side;
}

// Reads every submap file `manifest` lists, then restores them into `into`.
bool restore(const MapManifest& manifest, const std::string& dir, SubmapCollection* into,
             MapLoadReport* report, std::string* error) {
  const std::string manifest_path = (fs::path(dir) / kManifestFileName).string();
  if (!sameGeometry(manifest.config.layer, into->config().layer)) {
    return setError(error, manifest_path + ": the map's layer geometry (voxel size " +
                               std::to_string(manifest.config.layer.voxel_size) + ", " +
                               std::to_string(manifest.config.layer.voxels_per_side) +
                               " voxels per side) differs from the collection's");
  }
  if (!into->empty() ||
      (!manifest.submaps.empty() && into->nextSubmapId() > manifest.submaps.front().id)) {
    return setError(error, manifest_path +
                               ": the collection to load into is not empty (or has "
                               "assigned ids at or above the map's first id)");
  }
  MapLoadReport result;
  result.generation = manifest.generation;
  result.counters = manifest.counters;
  result.maintenance = manifest.maintenance;
  std::error_code ec;
  result.bytes_read = fs::file_size(manifest_path, ec);
  std::vector<TsdfLayer> layers;
  layers.reserve(manifest.submaps.size());
  for (const SubmapRecord& record : manifest.submaps) {
    std::optional<TsdfLayer> layer =
        readSubmapFile(dir, record.file, record.id, manifest.config.layer, error);
    if (!layer) return false;
    result.blocks += layer->numBlocks();
    result.bytes_read += record.file.file_size;
    layers.push_back(std::move(*layer));
  }
  std::unordered_set<std::string> listed;
  for (const SubmapRecord& record : manifest.submaps) listed.insert(record.file.file_name);
  for (const fs::directory_entry& entry : fs::directory_iterator(dir, ec)) {
    const std::string name = entry.path().filename().string();
    if (name != kManifestFileName && !listed.contains(name)) ++result.unlisted_files;
  }
  for (size_t i = 0; i < manifest.submaps.size(); ++i) {
    const SubmapRecord& record = manifest.submaps[i];
    const std::shared_ptr<Submap> submap =
        into->restoreSubmap(record.id, std::move(layers[i]), record.T_G_M, record.anchor_keyframe,
                            record.creation_time_ns, record.finished);
    for (const KeyframeId k : record.keyframe_ids) submap->addKeyframe(k);
  }
  into->reserveSubmapIds(manifest.next_submap_id);
  result.submaps = manifest.submaps.size();
  if (report != nullptr) *report = std::move(result);
  return true;
}

}  // namespace

std::optional<MapManifest> writeMapCheckpoint(const SubmapCollection& collection,
                                              const std::string& dir, const MapManifest* previous,
                                              const std::vector<SubmapId>& submaps_to_write,
                                              const std::map<std::string, int64_t>& counters,
                                              const MaintenanceStateSource& maintenance,
                                              MapSaveReport* report, std::string* error,
                                              std::chrono::milliseconds pause_before_each_file) {
  if (!ensureDirectory(dir, error)) return std::nullopt;
  MapSaveReport result;
  MapManifest manifest;
  manifest.generation =
      std::max(highestGeneration(dir), previous != nullptr ? previous->generation : 0) + 1;
  manifest.config = collection.config();
  manifest.counters = counters;

  std::unordered_map<SubmapId, const SubmapRecord*> previous_records;
  if (previous != nullptr) {
    for (const SubmapRecord& record : previous->submaps) previous_records[record.id] = &record;
  }
  const std::unordered_set<SubmapId> to_write(submaps_to_write.begin(), submaps_to_write.end());

  const SubmapCollectionState state = collection.snapshot();
  if (maintenance) {
    manifest.maintenance = restrictedTo(maintenance(), state);
    if (std::string e = manifest.maintenance.validate(); !e.empty()) {
      setError(error, (fs::path(dir) / kManifestFileName).string() +
                          ": not written, the maintenance state is inconsistent: " + e);
      return std::nullopt;
    }
  }
  manifest.next_submap_id = state.next_submap_id;
  if (state.active) manifest.active_submap_id = state.active->id();
  for (const std::shared_ptr<Submap>& submap : state.submaps) {
    SubmapRecord record;
    record.id = submap->id();
    record.anchor_keyframe = submap->anchorKeyframe();
    record.creation_time_ns = submap->creationTimeNs();
    record.T_G_M = submap->T_G_M();
    // Only the active submap is unfinished; one that createSubmap() is about to finish is
    // recorded finished, as it will be.
    record.finished = submap != state.active;
    record.keyframe_ids = submap->keyframeIds();
    const auto reuse = previous_records.find(record.id);
    std::error_code ec;
    if (!to_write.contains(record.id) && reuse != previous_records.end() &&
        fs::file_size(fs::path(dir) / reuse->second->file.file_name, ec) ==
            reuse->second->file.file_size &&
        !ec) {
      record.file = reuse->second->file;
      ++result.files_reused;
    } else {
      if (pause_before_each_file.count() > 0) std::this_thread::sleep_for(pause_before_each_file);
      std::optional<SubmapFileInfo> info =
          writeSubmapFile(*submap, dir, manifest.generation, error);
      if (!info) return std::nullopt;
      record.file = std::move(*info);
      ++result.files_written;
      result.bytes_written += record.file.file_size;
    }
    manifest.submaps.push_back(std::move(record));
  }
  if (pause_before_each_file.count() > 0) std::this_thread::sleep_for(pause_before_each_file);
  if (!writeManifest(manifest, dir, error)) return std::nullopt;
  std::error_code ec;
  result.bytes_written += fs::file_size(fs::path(dir) / kManifestFileName, ec);
  result.generation = manifest.generation;
  result.files_removed = removeUnlistedMapFiles(manifest, dir, nullptr);
  if (report != nullptr) *report = result;
  return manifest;
}

std::optional<MapManifest> saveMap(const SubmapCollection& collection, const std::string& dir,
                                   const std::map<std::string, int64_t>& counters,
                                   const MaintenanceStateSource& maintenance, MapSaveReport* report,
                                   std::string* error) {
  return writeMapCheckpoint(collection, dir, nullptr, {}, counters, maintenance, report, error);
}

bool loadMap(const std::string& dir, SubmapCollection* into, MapLoadReport* report,
             std::string* error) {
  const std::optional<MapManifest> manifest = readManifest(dir, error);
  return manifest && restore(*manifest, dir, into, report, error);
}

std::unique_ptr<SubmapCollection> loadMap(const std::string& dir, MapLoadReport* report,
                                          std::string* error) {
  const std::optional<MapManifest> manifest = readManifest(dir, error);
  if (!manifest) return nullptr;
  auto collection = std::make_unique<SubmapCollection>(manifest->config);
  if (!restore(*manifest, dir, collection.get(), report, error)) return nullptr;
  return collection;
}

size_t removeUnlistedMapFiles(const MapManifest& manifest, const std::string& dir,
                              std::string* error) {
  std::unordered_set<std::string> listed;
  for (const SubmapRecord& record : manifest.submaps) listed.insert(record.file.file_name);
  const std::string manifest_temp = std::string(kManifestFileName) + ".tmp.";
  std::vector<fs::path> doomed;
  std::error_code ec;
  for (const fs::directory_entry& entry : fs::directory_iterator(dir, ec)) {
    const std::string name = entry.path().filename().string();
    const bool submap_file = parseSubmapFileName(name, nullptr, nullptr) && !listed.contains(name);
    const bool temporary =
        (name.starts_with("submap_") && name.find(".tmp.") != std::string::npos) ||
        name.starts_with(manifest_temp);
    if (submap_file || temporary) doomed.push_back(entry.path());
  }
  if (ec) setError(error, dir + ": cannot list the map directory: " + ec.message());
  size_t removed = 0;
  bool failed = static_cast<bool>(ec);
  for (const fs::path& path : doomed) {
    std::error_code remove_ec;
    if (fs::remove(path, remove_ec)) {
      ++removed;
    } else if (remove_ec && !failed) {
      failed = true;
      setError(error, path.string() + ": cannot remove: " + remove_ec.message());
    }
  }
  return removed;
}

}  // namespace cblox
