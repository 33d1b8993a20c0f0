// cblox-map-verify: checks a map directory (a saved map or the mapper's checkpoint.dir; README
// "Map file format") the way cblox-mapper loads it, and prints what it holds. A directory with
// the tracker's map instead (its checkpoint.dir, README "Tracker map format") is checked the
// way cblox-tracker loads it (index, chunks, consistency, id lease) and described per keyframe.
//
//   cblox-map-verify DIR                 # summary and one line per submap
//   cblox-map-verify DIR --json          # the same as one JSON object (scripts/crash_test.sh)
//   cblox-map-verify DIR --manifest-only # the manifest alone (no submap file is read)
//
// It reads and verifies the manifest, then loads the whole map as the mapper does (loadMap:
// every listed submap file's header, size, XXH64 and contents), then encodes every loaded
// submap's voxels again and compares the XXH64 of those bytes with the file's: equal means
// the map in memory after a load is bit-identical to the files (the encoding is
// deterministic). It lists the files in DIR that the manifest does not list (left by an
// interrupted checkpoint; the mapper ignores and later removes them).
// Exit status: 0 the map is valid, 1 a problem (named on stderr and in the JSON "problems"),
// 2 usage.

#include <cinttypes>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/persistence/map_file_header.h"
#include "core/persistence/map_manifest.h"
#include "core/persistence/map_store.h"
#include "core/persistence/submap_file.h"
#include "core/persistence/sparse_map_file.h"
#include "daemon/common/cli.h"
#include "daemon/tools/tracker_map_json.h"

namespace cblox {
namespace {

namespace fs = std::filesystem;

std::string hex(uint64_t v) {
  char text[24];
  std::snprintf(text, sizeof(text), "%016" PRIx64, v);
  return text;
}

// Files in `dir` other than the manifest and the files it lists.
std::vector<std::string> unlistedFiles(const std::string& dir, const MapManifest& manifest) {
  std::set<std::string> listed;
  for (const SubmapRecord& record : manifest.submaps) listed.insert(record.file.file_name);
  std::vector<std::string> out;
  std::error_code ec;
  for (const fs::directory_entry& entry : fs::directory_iterator(dir, ec)) {
    const std::string name = entry.path().filename().string();
    if (name != kManifestFileName && !listed.contains(name)) out.push_back(name);
  }
  std::sort(out.begin(), out.end());
  return out;
}

nlohmann::json describe(const std::string& dir, bool manifest_only,
                        std::vector<std::string>* problems) {
  nlohmann::json out;
  out["dir"] = dir;
  std::string error;
  const std::optional<MapManifest> manifest = readManifest(dir, &error);
  if (!manifest) {
    problems->push_back(error);
    return out;
  }
  out["generation"] = manifest->generation;
  out["next_submap_id"] = manifest->next_submap_id;
  out["active_submap_id"] =
      manifest->active_submap_id ? nlohmann::json(*manifest->active_submap_id) : nlohmann::json();
  out["voxel_size"] = manifest->config.layer.voxel_size;
  out["voxels_per_side"] = manifest->config.layer.voxels_per_side;
  out["counters"] = manifest->counters;
  size_t keyframes = 0, landmarks = 0;
  for (const SubvolumeLandmarks& s : manifest->maintenance.subvolumes) {
    keyframes += s.keyframes.size();
    for (const KeyframeLandmarks& k : s.keyframes) landmarks += k.landmark_ids.size();
  }
  out["maintenance"] = {{"subvolumes", manifest->maintenance.subvolumes.size()},
                        {"keyframes", keyframes},
                        {"landmark_observations", landmarks},
                        {"backoffs", manifest->maintenance.backoffs.size()}};
  out["unlisted_files"] = unlistedFiles(dir, *manifest);

  std::unique_ptr<SubmapCollection> loaded;
  if (!manifest_only) {
    MapLoadReport report;
    loaded = loadMap(dir, &report, &error);
    if (!loaded) problems->push_back(error);
    // A manifest committed between the two reads would make them disagree.
    if (loaded && report.generation != manifest->generation) {
      problems->push_back(dir + ": the manifest changed while it was read (generation " +
                          std::to_string(manifest->generation) + " then " +
                          std::to_string(report.generation) + "); run again");
      loaded.reset();
    }
  }
  uint64_t blocks = 0;
  nlohmann::json submaps = nlohmann::json::array();
  for (const SubmapRecord& record : manifest->submaps) {
    uint64_t generation = 0;
    parseSubmapFileName(record.file.file_name, nullptr, &generation);
    nlohmann::json s = {{"id", record.id},
                        {"generation", generation},
                        {"file", record.file.file_name},
                        {"file_size", record.file.file_size},
                        {"xxh64", hex(record.file.payload_xxh64)},
                        {"blocks", record.file.num_blocks},
                        {"finished", record.finished},
                        {"anchor_keyframe", record.anchor_keyframe},
                        {"keyframes", record.keyframe_ids}};
    blocks += record.file.num_blocks;
    if (loaded) {
      const std::shared_ptr<Submap> submap = loaded->getSubmap(record.id);
      const std::string bytes = encodeSubmapFile(record.id, submap->layer());
      const uint64_t again = mapFileChecksum(std::string_view(bytes).substr(kMapFileHeaderBytes));
      s["loaded_xxh64"] = hex(again);
      if (again != record.file.payload_xxh64) {
        problems->push_back(dir + "/" + record.file.file_name +
                            ": the loaded voxels encode to XXH64 " + hex(again) +
                            ", the file holds " + hex(record.file.payload_xxh64));
      }
    }
    submaps.push_back(std::move(s));
  }
  out["submaps"] = std::move(submaps);
  out["blocks"] = blocks;
  out["verified"] = manifest_only ? "manifest" : "manifest, files, loaded voxels";
  return out;
}

void printText(const nlohmann::json& m) {
  std::printf("%s: generation %s, %zu submaps, %s blocks (verified: %s)\n",
              m["dir"].get<std::string>().c_str(), m["generation"].dump().c_str(),
              m["submaps"].size(), m["blocks"].dump().c_str(),
              m["verified"].get<std::string>().c_str());
  std::printf(
      "maintenance: %s subvolumes with landmarks (%s keyframes, %s landmark observations), %s "
      "pair back-offs\n",
      m["maintenance"]["subvolumes"].dump().c_str(), m["maintenance"]["keyframes"].dump().c_str(),
      m["maintenance"]["landmark_observations"].dump().c_str(),
      m["maintenance"]["backoffs"].dump().c_str());
  std::printf("%6s %6s %-28s %10s %-16s %8s %s\n", "id", "gen", "file", "bytes", "xxh64", "blocks",
              "state");
  for (const nlohmann::json& s : m["submaps"]) {
    std::printf("%6s %6s %-28s %10s %-16s %8s %s\n", s["id"].dump().c_str(),
                s["generation"].dump().c_str(), s["file"].get<std::string>().c_str(),
                s["file_size"].dump().c_str(), s["xxh64"].get<std::string>().c_str(),
                s["blocks"].dump().c_str(), s["finished"].get<bool>() ? "finished" : "active");
  }
  for (const nlohmann::json& name : m["unlisted_files"]) {
    std::printf("not listed (ignored): %s\n", name.get<std::string>().c_str());
  }
}

int run(int argc, char** argv) {
  std::string dir;
  bool json = false, manifest_only = false;
  CLI::App app(
      "cblox-map-verify: verifies a map directory (every checksum, and the map as "
      "loaded) and prints its generation and submaps");
  app.add_option("dir", dir, "map directory (a saved map or checkpoint.dir)")->required();
  app.add_flag("--json", json, "print one JSON object instead of text");
  app.add_flag("--manifest-only", manifest_only, "read the manifest alone (no submap file)");
  app.footer("Exit status: 0 valid, 1 a problem (named), 2 usage.");
  if (const std::optional<int> code = parseCommandLine(app, argc, argv)) return *code;

  std::vector<std::string> problems;
  nlohmann::json m;
  const bool tracker = hasTrackerMap(dir) && !fs::exists(fs::path(dir) / kManifestFileName);
  try {
    m = tracker ? describeTrackerMap(dir, &problems) : describe(dir, manifest_only, &problems);
  } catch (const std::exception& e) {
    problems.push_back(dir + ": " + e.what());
  }
  m["problems"] = problems;
  m["ok"] = problems.empty();
  if (json) {
    std::printf("%s\n", m.dump().c_str());
  } else if (m.contains("submaps")) {
    printText(m);
  } else if (m.contains("keyframes")) {
    std::printf("%s: tracker map, generation %s, epoch %s, %s keyframes (%s good), %s landmarks, "
                "%zu chunk files (verified: %s)\n",
                dir.c_str(), m["generation"].dump().c_str(), m["map_epoch"].dump().c_str(),
                std::to_string(m["keyframes"].size()).c_str(), m["good_keyframes"].dump().c_str(),
                m["landmarks"].dump().c_str(), m["chunks"].size(),
                m["verified"].get<std::string>().c_str());
  }
  for (const std::string& p : problems) std::fprintf(stderr, "cblox-map-verify: %s\n", p.c_str());
  return problems.empty() ? 0 : 1;
}

}  // namespace
}  // namespace cblox

int main(int argc, char** argv) { return cblox::run(argc, argv); }
