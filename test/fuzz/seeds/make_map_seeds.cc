// Writes the map-file seed corpora of the fuzz targets (test/fuzz/corpus/): a tiny map of two
// submaps (one finished, one active, a few blocks, keyframes) saved with saveMap, then its
// manifest and a submap file in the forms fuzz_map_manifest, fuzz_submap_file and
// fuzz_load_map read (first byte even: payload, sealed by the target; odd: the whole file),
// and a few corrupt copies. The manifest's version 2 seed (valid_v2_file) was written by the
// version 2 build and is kept. Run by hand after the map format changes:
//   build/test/fuzz/make_map_seeds test/fuzz/corpus

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <string>

#include "core/persistence/map_file_header.h"
#include "core/persistence/map_store.h"
#include "core/submap/submap_collection.h"

namespace cblox {
namespace {
namespace fs = std::filesystem;

std::string readAll(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void write(const fs::path& path, const std::string& bytes) {
  fs::create_directories(path.parent_path());
  std::ofstream(path, std::ios::binary) << bytes;
}

// A block of voxels near a surface, in the active submap.
void fillBlock(Submap* submap, const BlockIndex& index, float distance) {
  Submap::WriteLock lock = submap->lockForIntegration();
  Block* block = lock.layer().allocateBlock(index);
  for (int i = 0; i < block->numVoxels(); i += 3) {
    TsdfVoxel& voxel = block->voxel(i);
    voxel.distance = distance + 0.001f * static_cast<float>(i % 17);
    voxel.weight = 1.0f + static_cast<float>(i % 5);
    voxel.color = Color{static_cast<uint8_t>(i), 128, 40};
  }
}

}  // namespace
}  // namespace cblox

int main(int argc, char** argv) {
  using namespace cblox;
  if (argc != 2) {
    std::fprintf(stderr, "usage: make_map_seeds CORPUS_DIR (test/fuzz/corpus)\n");
    return 2;
  }
  const fs::path root(argv[1]);
  SubmapCollectionConfig config;
  config.layer.voxels_per_side = 4;  // small files
  SubmapCollection collection(config);
  auto first = collection.createSubmap(Transformationd(), 0, 1000);
  fillBlock(first.get(), BlockIndex(0, 0, 0), 0.01f);
  fillBlock(first.get(), BlockIndex(1, 0, -1), -0.02f);
  first->addKeyframe(1);
  auto second = collection.createSubmap(
      Transformationd(Eigen::Quaterniond::Identity(), Eigen::Vector3d(1.0, 0.0, 0.0)), 2, 2000);
  fillBlock(second.get(), BlockIndex(0, 1, 0), 0.03f);

  const fs::path dir = fs::temp_directory_path() / "cblox-make-map-seeds";
  fs::remove_all(dir);
  std::string error;
  // A maintenance section (manifest version 3): the keyframes' landmark sets, a back-off.
  FusionSchedulerState maintenance;
  maintenance.subvolumes = {{0, {{0, {1, 2, 300}}, {1, {2, 5, 1u << 20}}}}, {1, {{2, {300, 301}}}}};
  maintenance.backoffs = {{0, 1, 1, 2.5}};
  const auto manifest = saveMap(
      collection, dir.string(), {{"frames_integrated", 12}}, [&] { return maintenance; },
      nullptr, &error);
  if (!manifest) {
    std::fprintf(stderr, "make_map_seeds: %s\n", error.c_str());
    return 1;
  }
  const std::string manifest_file = readAll(dir / "manifest.cbmap");
  const std::string manifest_payload = manifest_file.substr(kMapFileHeaderBytes);
  std::string load_map = manifest_payload;
  bool first_submap = true;
  for (const fs::directory_entry& entry : fs::directory_iterator(dir)) {
    const std::string name = entry.path().filename().string();
    if (name == "manifest.cbmap") continue;
    const std::string file = readAll(entry.path());
    load_map += "\n@@@@\n" + name + "\n" + file;
    if (first_submap) {
      write(root / "fuzz_submap_file" / "valid_sealed", '\0' + file.substr(kMapFileHeaderBytes));
      write(root / "fuzz_submap_file" / "valid_file", '\1' + file);
      std::string flipped = file;
      flipped[flipped.size() / 2] ^= 0x40;
      write(root / "fuzz_submap_file" / "invalid_checksum", '\1' + flipped);
      first_submap = false;
    }
  }
  write(root / "fuzz_map_manifest" / "valid_sealed", '\0' + manifest_payload);
  write(root / "fuzz_map_manifest" / "valid_file", '\1' + manifest_file);
  write(root / "fuzz_map_manifest" / "invalid_truncated", '\1' + manifest_file.substr(0, 40));
  write(root / "fuzz_load_map" / "valid_map", load_map);
  write(root / "fuzz_load_map" / "invalid_no_submap_files", manifest_payload);
  fs::remove_all(dir);
  std::printf("map seeds written under %s\n", root.c_str());
  return 0;
}
