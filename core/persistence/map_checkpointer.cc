#include "core/persistence/map_checkpointer.h"

#include <chrono>
#include <memory>
#include <utility>
#include <vector>

#include "core/persistence/map_store.h"

namespace cblox {

MapCheckpointer::MapCheckpointer(std::string dir) : dir_(std::move(dir)) {}

std::optional<MapCheckpointReport> MapCheckpointer::checkpoint(
    const SubmapCollection& collection, const std::map<std::string, int64_t>& counters,
    const MaintenanceStateSource& maintenance, std::string* error) {
  const auto start = std::chrono::steady_clock::now();
  // The revisions are read BEFORE writeMapCheckpoint copies any voxel: a change made while
  // (or after) a submap is written bumps its revision past the one recorded here, so the next
  // checkpoint writes that submap again. Reading them afterwards could record a revision
  // whose change the file does not hold.
  std::map<SubmapId, uint64_t> revisions;
  std::vector<SubmapId> to_write;
  for (const std::shared_ptr<Submap>& submap : collection.submaps()) {
    const uint64_t revision = submap->revision();
    revisions.emplace(submap->id(), revision);
    const auto it = written_revisions_.find(submap->id());
    if (it == written_revisions_.end() || it->second != revision) to_write.push_back(submap->id());
  }
  MapSaveReport save;
  std::optional<MapManifest> manifest =
      writeMapCheckpoint(collection, dir_, previous_ ? &*previous_ : nullptr, to_write, counters,
                         maintenance, &save, error, pause_);
  if (!manifest) return std::nullopt;

  // Every listed file holds its submap as of (at least) the revision read above. A submap
  // created after that read has no revision recorded, so it is written again next time.
  std::map<SubmapId, uint64_t> written;
  for (const SubmapRecord& record : manifest->submaps) {
    const auto it = revisions.find(record.id);
    if (it != revisions.end()) written.emplace(record.id, it->second);
  }
  written_revisions_ = std::move(written);
  previous_ = std::move(manifest);

  MapCheckpointReport report;
  report.generation = save.generation;
  report.submaps = previous_->submaps.size();
  report.submaps_written = save.files_written;
  report.submaps_reused = save.files_reused;
  report.bytes_written = save.bytes_written;
  report.milliseconds =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  return report;
}

void MapCheckpointer::adoptLoaded(const MapManifest& manifest, const SubmapCollection& collection) {
  written_revisions_.clear();
  for (const SubmapRecord& record : manifest.submaps) {
    if (const std::shared_ptr<Submap> submap = collection.getSubmap(record.id)) {
      written_revisions_.emplace(record.id, submap->revision());
    }
  }
  previous_ = manifest;
}

}  // namespace cblox
