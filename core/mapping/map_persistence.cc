#include "core/mapping/map_persistence.h"

#include <chrono>
#include <optional>

#include "core/common/text_format.h"
#include "core/mapping/output_path.h"
#include "core/persistence/map_store.h"

namespace cblox {

MapperReply saveMapToOutputDir(const SubmapCollection& collection,
                               const std::filesystem::path& output_dir, const std::string& dir_arg,
                               const std::map<std::string, int64_t>& counters,
                               const MaintenanceStateSource& maintenance) {
  MapperReply reply;
  std::string error;
  const auto dir = writableOutputPath(output_dir, dir_arg, &error);
  if (!dir) {
    reply.message = error;
    return reply;
  }
  const auto start = std::chrono::steady_clock::now();
  MapSaveReport report;
  const std::optional<MapManifest> manifest =
      saveMap(collection, dir->string(), counters, maintenance, &report, &error);
  if (!manifest) {
    reply.message = "map not saved: " + error;
    return reply;
  }
  uint64_t blocks = 0;
  for (const SubmapRecord& record : manifest->submaps) blocks += record.file.num_blocks;
  const double seconds = secondsSince(start);
  reply.ok = true;
  reply.message = "saved " + dir->string() + ": " + std::to_string(manifest->submaps.size()) +
                  " subvolumes, " + std::to_string(blocks) + " blocks, " +
                  std::to_string(report.bytes_written) + " bytes in " + fixed(seconds, 3) + " s";
  reply.values = {{"path", dir->string()},
                  {"submaps", std::to_string(manifest->submaps.size())},
                  {"blocks", std::to_string(blocks)},
                  {"bytes", std::to_string(report.bytes_written)},
                  {"seconds", fixed(seconds, 3)}};
  return reply;
}

}  // namespace cblox
