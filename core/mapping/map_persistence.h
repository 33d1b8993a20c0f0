#pragma once

// The map over the command channel (the worker's command save_map): the subvolume map saved
// as a map directory (core/persistence/map_store.h) inside the output directory.

#include <cstdint>
#include <filesystem>
#include <map>
#include <string>

#include "core/mapping/mapper_command.h"
#include "core/persistence/map_store.h"
#include "core/submap/submap_collection.h"

namespace cblox {

/// Saves `collection` (saveMap: every submap file, then the manifest with `counters` and the
/// map maintenance's state from `maintenance`) into
/// the map directory `dir`, resolved inside `output_dir` (resolveOutputPath; confined there
/// on disk too, staysInsideOnDisk) and created if absent. Reads finished layers in place and
/// copies an active one under its layer lock (writeSubmapFile), so call it only where
/// finished layers may be read: the mapper's worker thread (SubmapCollection's rule). The
/// reply says what was written (values path, submaps, blocks, bytes: the sum of the file
/// sizes, seconds) or why nothing was committed (reply.ok false; the message names the file
/// or the path). Never throws for a bad path.
MapperReply saveMapToOutputDir(const SubmapCollection& collection,
                               const std::filesystem::path& output_dir, const std::string& dir,
                               const std::map<std::string, int64_t>& counters,
                               const MaintenanceStateSource& maintenance);

}  // namespace cblox
