// Writes the seed corpus of fuzz_tracker_map (test/fuzz/corpus/fuzz_tracker_map/): a tiny
// consistent sparse map (three keyframes, one culled, two landmarks) in every form the target
// reads (see its first lines), and a few corrupt copies. Run by hand after the tracker map
// format changes:
//   build/test/fuzz/make_tracker_map_seeds test/fuzz/corpus

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>

#include "core/persistence/byte_codec.h"
#include "core/persistence/sparse_map_file.h"
#include "core/persistence/zstd_blob.h"
#include "test/fuzz/support/fuzz_files.h"

namespace cblox {
namespace {
namespace fs = std::filesystem;

std::shared_ptr<FrameFeatures> features(int n) {
  auto f = std::make_shared<FrameFeatures>();
  for (int i = 0; i < n; ++i) {
    f->keypoints.push_back({10.0f + 20.0f * i, 30.0f + 5.0f * i, 12.5f * i, 40.0f, i % 4});
    OrbDescriptor d;
    d.words = {0x0123456789abcdefULL * (i + 1), 0xfedcba9876543210ULL ^ i, 0xffULL << i, 42};
    f->descriptors.push_back(d);
    f->right_u.push_back(i % 2 == 0 ? 5.0f + 20.0f * i : -1.0f);
    f->depth.push_back(i % 2 == 0 ? 2.5f : -1.0f);
  }
  return f;
}

TrackerMapIndex tinyMap() {
  TrackerMapIndex index;
  TrackerMapState& s = index.state;
  s.generation = 1;
  s.camera.intrinsics = {229.0, 229.0, 187.5, 119.5, 376, 240};
  s.camera.baseline_m = 0.11;
  SparseMapSnapshot& m = s.map;
  for (int i = 0; i < 3; ++i) {
    KeyframeSnapshot k;
    k.id = i;
    k.frame_id = 10 * i;
    k.timestamp_ns = 1'000'000'000LL * i;
    k.T_C_G = Transformationd(Eigen::Quaterniond::Identity(), Eigen::Vector3d(0.1 * i, 0, 0));
    k.first_connection_pending = i == 0;
    k.parent = i - 1;
    k.bad = i == 2;
    k.features = k.bad ? std::make_shared<FrameFeatures>() : features(4);
    m.keyframes.push_back(k);
  }
  m.keyframes[0].connections = {{1, 2}};
  m.keyframes[1].connections = {{0, 2}};
  for (int j = 0; j < 2; ++j) {
    LandmarkSnapshot l;
    l.id = 5 + j;
    l.p_G = Eigen::Vector3d(0.5 * j, 0.2, 2.5);
    l.normal = Eigen::Vector3d(0, 0, 1);
    l.min_distance = 1.0;
    l.max_distance = 4.0;
    l.reference = 0;
    l.observations = {{0, static_cast<uint32_t>(j)}, {1, static_cast<uint32_t>(j + 2)}};
    m.landmarks.push_back(l);
  }
  m.next_landmark_id = 7;
  index.chunks.push_back({keyframeChunkFileName(0, 1), 0, 0});
  index.keyframe_chunk = {0, 0, kNoKeyframeChunk};
  return index;
}

std::string raw(const std::string& payload) {
  std::string out;
  if (const std::string e = readZstdBlob(payload, &out); !e.empty()) {
    std::fprintf(stderr, "%s\n", e.c_str());
    std::exit(1);
  }
  return out;
}

void write(const fs::path& path, char mode, const std::string& bytes) {
  std::ofstream(path, std::ios::binary) << mode << bytes;
}

}  // namespace
}  // namespace cblox

int main(int argc, char** argv) {
  using namespace cblox;
  if (argc != 2) {
    std::fprintf(stderr, "usage: make_tracker_map_seeds CORPUS_DIR (test/fuzz/corpus)\n");
    return 2;
  }
  const fs::path dir = fs::path(argv[1]) / "fuzz_tracker_map";
  fs::create_directories(dir);
  const TrackerMapIndex index = tinyMap();
  const std::string problem = index.state.map.validate(8);
  if (!problem.empty()) {
    std::fprintf(stderr, "the seed map is inconsistent: %s\n", problem.c_str());
    return 1;
  }
  const std::string index_payload = encodeTrackerMapIndex(index);
  std::vector<const KeyframeSnapshot*> good = {&index.state.map.keyframes[0],
                                               &index.state.map.keyframes[1]};
  const std::string chunk_payload = encodeKeyframeChunk(good);
  std::string lease;
  persistence_detail::ByteWriter w(&lease);
  w.i32(0);
  w.i64(64);
  w.u64(70000);
  const std::string sep(fuzz::kPartSeparator);
  write(dir / "index_payload", 0, index_payload);
  write(dir / "index_raw", 1, raw(index_payload));
  write(dir / "chunk_payload", 2, chunk_payload);
  write(dir / "chunk_raw", 3, raw(chunk_payload));
  write(dir / "directory", 4, raw(index_payload) + sep + raw(chunk_payload) + sep + lease);
  write(dir / "directory_no_lease", 4, raw(index_payload) + sep + raw(chunk_payload) + sep);
  std::string truncated = raw(index_payload);
  truncated.resize(truncated.size() / 2);
  write(dir / "index_raw_truncated", 1, truncated);
  std::string forged = index_payload;
  forged[7] = 0x40;  // an uncompressed length far beyond the frame
  write(dir / "index_payload_forged_length", 0, forged);
  std::printf("wrote %s\n", dir.c_str());
  return 0;
}
