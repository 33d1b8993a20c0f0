// The tracker's map survives a restart: a map built on the simulated room is checkpointed,
// loaded and restored into a new SlamSystem, which holds exactly the same map, relocalizes
// in it at the true pose, and continues it with new keyframe ids. The next checkpoint writes
// only the new keyframes' features. Damaged files are refused with a message.

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "core/persistence/id_lease.h"
#include "core/persistence/pose_codec.h"
#include "core/persistence/sparse_map_file.h"
#include "core/persistence/tracker_map_checkpointer.h"
#include "core/tracking/slam_system.h"
#include "drivers/open_frame_source.h"

namespace cblox {
namespace {

namespace fs = std::filesystem;

void expectSamePose(const Transformationd& a, const Transformationd& b, const std::string& what) {
  EXPECT_EQ(a.translation(), b.translation()) << what;
  EXPECT_LT(a.rotation().angularDistance(b.rotation()), 1e-12) << what;
}

void expectSameFeatures(const FrameFeatures& a, const FrameFeatures& b, const std::string& what) {
  ASSERT_EQ(a.size(), b.size()) << what;
  for (size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a.keypoints[i].u, b.keypoints[i].u) << what;
    EXPECT_EQ(a.keypoints[i].v, b.keypoints[i].v) << what;
    EXPECT_EQ(a.keypoints[i].angle_deg, b.keypoints[i].angle_deg) << what;
    EXPECT_EQ(a.keypoints[i].response, b.keypoints[i].response) << what;
    EXPECT_EQ(a.keypoints[i].octave, b.keypoints[i].octave) << what;
    EXPECT_EQ(a.descriptors[i], b.descriptors[i]) << what;
  }
  EXPECT_EQ(a.right_u, b.right_u) << what;
  EXPECT_EQ(a.depth, b.depth) << what;
}

// Every field of two snapshots, exactly (poses to rounding of the quaternion normalisation).
void expectSameSnapshot(const SparseMapSnapshot& a, const SparseMapSnapshot& b) {
  ASSERT_EQ(a.keyframes.size(), b.keyframes.size());
  for (size_t i = 0; i < a.keyframes.size(); ++i) {
    const KeyframeSnapshot& x = a.keyframes[i];
    const KeyframeSnapshot& y = b.keyframes[i];
    const std::string what = "keyframe " + std::to_string(i);
    EXPECT_EQ(x.id, y.id) << what;
    EXPECT_EQ(x.frame_id, y.frame_id) << what;
    EXPECT_EQ(x.timestamp_ns, y.timestamp_ns) << what;
    expectSamePose(x.T_C_G, y.T_C_G, what);
    EXPECT_EQ(x.bad, y.bad) << what;
    EXPECT_EQ(x.first_connection_pending, y.first_connection_pending) << what;
    EXPECT_EQ(x.parent, y.parent) << what;
    if (x.bad) expectSamePose(x.T_parent_this, y.T_parent_this, what);
    EXPECT_EQ(x.connections, y.connections) << what;
    EXPECT_EQ(x.loop_edges, y.loop_edges) << what;
    expectSameFeatures(*x.features, *y.features, what);
  }
  ASSERT_EQ(a.landmarks.size(), b.landmarks.size());
  for (size_t i = 0; i < a.landmarks.size(); ++i) {
    const LandmarkSnapshot& x = a.landmarks[i];
    const LandmarkSnapshot& y = b.landmarks[i];
    const std::string what = "landmark " + std::to_string(x.id);
    EXPECT_EQ(x.id, y.id) << what;
    EXPECT_EQ(x.p_G, y.p_G) << what;
    EXPECT_EQ(x.normal, y.normal) << what;
    EXPECT_EQ(x.min_distance, y.min_distance) << what;
    EXPECT_EQ(x.max_distance, y.max_distance) << what;
    EXPECT_EQ(x.descriptor, y.descriptor) << what;
    EXPECT_EQ(x.reference, y.reference) << what;
    EXPECT_EQ(x.first_keyframe_id, y.first_keyframe_id) << what;
    EXPECT_EQ(x.visible, y.visible) << what;
    EXPECT_EQ(x.found, y.found) << what;
    EXPECT_EQ(x.observations, y.observations) << what;
  }
  EXPECT_EQ(a.next_landmark_id, b.next_landmark_id);
  EXPECT_EQ(a.change_index, b.change_index);
}

class SparseMapResumeTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    std::string error;
    vocabulary_ = new BinaryVocabulary(*BinaryVocabulary::load(CBLOX_DEFAULT_VOCABULARY, &error));
    SourceConfig options;
    options.trajectory = "loop";
    options.max_frames = 160;
    std::unique_ptr<FrameSource> source = openFrameSource("sim:room", options, &error);
    ASSERT_NE(source, nullptr) << error;
    calibration_ = *source->info().stereo;
    frames_ = new std::vector<CaptureFrame>;
    CaptureFrame frame;
    while (source->next(&frame, &error) == FrameSource::Status::kFrame) frames_->push_back(frame);
    ASSERT_EQ(frames_->size(), 160u);
  }
  static void TearDownTestSuite() {
    delete vocabulary_;
    delete frames_;
  }
  void SetUp() override {
    dir_ = fs::path(::testing::TempDir()) /
           ("tracker_map_" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
    fs::remove_all(dir_);
  }

  static TrackingCamera camera() {
    return makeTrackingCamera(calibration_.intrinsics, calibration_.baseline_m);
  }
  static SlamSystemConfig config() {
    SlamSystemConfig c;
    c.loop_closing_enabled = false;
    return c;
  }
  static TrackerMapState stateOf(const SlamSystem& slam) {
    TrackerMapState state;
    state.map_epoch = 3;
    state.camera.intrinsics = calibration_.intrinsics;
    state.camera.baseline_m = calibration_.baseline_m;
    state.map = slam.snapshot();
    return state;
  }
  // Tracks frames [begin, end) of the room loop; frame i gets id and time from i + offset.
  static void track(SlamSystem* slam, size_t begin, size_t end, uint64_t offset = 0) {
    for (size_t i = begin; i < end; ++i) {
      const CaptureFrame& f = (*frames_)[i];
      const TrackingResult r =
          slam->trackStereo(i + offset, static_cast<int64_t>(i + offset + 1) * 50'000'000,
                            f.left, f.right, (*frames_)[0].T_G_C->inverse());
      ASSERT_EQ(r.state, TrackingState::kOk) << "frame " << i << ": " << r.reason;
      slam->waitUntilIdle();
    }
  }

  static BinaryVocabulary* vocabulary_;
  static RectifiedStereoCalibration calibration_;
  static std::vector<CaptureFrame>* frames_;
  fs::path dir_;
};
BinaryVocabulary* SparseMapResumeTest::vocabulary_ = nullptr;
RectifiedStereoCalibration SparseMapResumeTest::calibration_;
std::vector<CaptureFrame>* SparseMapResumeTest::frames_ = nullptr;

TEST_F(SparseMapResumeTest, SavedMapLoadsRestoresRelocalizesAndContinues) {
  SlamSystem first(camera(), config(), vocabulary_);
  track(&first, 0, 100);
  const TrackerMapState saved = stateOf(first);
  first.stop();
  const size_t num_keyframes = saved.map.keyframes.size();
  ASSERT_GT(num_keyframes, 5u);
  ASSERT_GT(saved.map.landmarks.size(), 500u);

  TrackerMapCheckpointer checkpointer(dir_.string());
  std::string error;
  const auto report = checkpointer.checkpoint(saved, &error);
  ASSERT_TRUE(report.has_value()) << error;
  EXPECT_EQ(report->generation, 1u);
  EXPECT_EQ(report->keyframes, num_keyframes);
  size_t good = 0;
  for (const KeyframeSnapshot& k : saved.map.keyframes) good += k.bad ? 0 : 1;
  EXPECT_EQ(report->keyframes_written, good);
  std::printf("checkpoint: %zu keyframes (%zu good), %zu landmarks, %.1f KiB, %.1f ms\n",
              num_keyframes, good, report->landmarks, report->bytes_written / 1024.0,
              report->milliseconds);

  TrackerMapIndex index;
  const auto loaded = loadTrackerMap(dir_.string(), &error, &index);
  ASSERT_TRUE(loaded.has_value()) << error;
  EXPECT_EQ(loaded->generation, 1u);
  EXPECT_EQ(loaded->map_epoch, 3);
  EXPECT_EQ(loaded->camera.intrinsics.fx, calibration_.intrinsics.fx);
  EXPECT_EQ(loaded->camera.baseline_m, calibration_.baseline_m);
  expectSameSnapshot(saved.map, loaded->map);

  // A new tracker restores it: the same map, every good keyframe a relocalization candidate.
  SlamSystem second(camera(), config(), vocabulary_);
  second.restore(loaded->map);
  expectSameSnapshot(saved.map, second.snapshot());
  // Bit-identical, as the digests of the crash test see it.
  const SparseMapSnapshot restored = second.snapshot();
  EXPECT_EQ(landmarksDigest(restored), landmarksDigest(saved.map));
  for (size_t i = 0; i < num_keyframes; ++i) {
    EXPECT_EQ(keyframeFeaturesDigest(restored.keyframes[i]),
              keyframeFeaturesDigest(saved.map.keyframes[i]));
    EXPECT_EQ(keyframeStateDigest(restored.keyframes[i]),
              keyframeStateDigest(saved.map.keyframes[i]));
  }
  EXPECT_EQ(second.databaseSize(), good);

  // It is lost in that map, and finds itself at frame 40's place, at the true pose.
  const CaptureFrame& back = (*frames_)[40];
  const TrackingResult r = second.trackStereo(1000, 1000 * 50'000'000LL, back.left, back.right);
  ASSERT_EQ(r.state, TrackingState::kOk) << r.reason;
  EXPECT_TRUE(r.relocalized);
  const double error_m = (r.T_C_G->inverse().translation() - back.T_G_C->translation()).norm();
  std::printf("relocalized after the restart: error %.4f m, %d inliers\n", error_m, r.inliers);
  EXPECT_LT(error_m, 0.05);

  // It continues the map past where the first run stopped, with new keyframe ids.
  track(&second, 41, 160, 1000);
  const TrackerMapState continued = stateOf(second);
  second.stop();
  ASSERT_GT(continued.map.keyframes.size(), num_keyframes);
  // Its newest keyframe sits where the camera truly was (a wrong relocalization would have
  // continued the map from a wrong place).
  const KeyframeSnapshot& newest = continued.map.keyframes.back();
  ASSERT_GE(newest.frame_id, 1041u);
  const CaptureFrame& truth = (*frames_)[newest.frame_id - 1000];
  const double newest_error_m =
      (newest.T_C_G.inverse().translation() - truth.T_G_C->translation()).norm();
  std::printf("newest keyframe %lld (frame %llu): %.4f m from the truth\n",
              static_cast<long long>(newest.id), static_cast<unsigned long long>(newest.frame_id - 1000),
              newest_error_m);
  EXPECT_LT(newest_error_m, 0.05);

  // The next checkpoint writes only the new keyframes; the first chunk is listed again.
  checkpointer.adoptLoaded(index);
  const auto next = checkpointer.checkpoint(continued, &error);
  ASSERT_TRUE(next.has_value()) << error;
  EXPECT_EQ(next->generation, 2u);
  size_t fresh = 0;
  for (size_t i = num_keyframes; i < continued.map.keyframes.size(); ++i) {
    fresh += continued.map.keyframes[i].bad ? 0 : 1;
  }
  EXPECT_EQ(next->keyframes_written, fresh);
  const auto reloaded = loadTrackerMap(dir_.string(), &error);
  ASSERT_TRUE(reloaded.has_value()) << error;
  expectSameSnapshot(continued.map, reloaded->map);
  EXPECT_TRUE(fs::exists(dir_ / keyframeChunkFileName(3, 1)));
  EXPECT_TRUE(fs::exists(dir_ / keyframeChunkFileName(3, 2)));
}

TEST_F(SparseMapResumeTest, IdFloorsSkipIdsThatMayHaveBeenPublished) {
  SlamSystem first(camera(), config(), vocabulary_);
  track(&first, 0, 30);
  const SparseMapSnapshot saved = first.snapshot();
  first.stop();
  const auto n = static_cast<KeyframeId>(saved.keyframes.size());
  SlamSystem second(camera(), config(), vocabulary_);
  second.restore(saved, n + 10, saved.next_landmark_id + 5000);
  const SparseMapSnapshot restored = second.snapshot();
  ASSERT_EQ(restored.keyframes.size(), static_cast<size_t>(n + 10));
  for (KeyframeId id = n; id < n + 10; ++id) {
    EXPECT_TRUE(restored.keyframes[static_cast<size_t>(id)].bad) << id;
  }
  EXPECT_EQ(restored.next_landmark_id, saved.next_landmark_id + 5000);
  // Relocalize, then move on until a keyframe is made: its id is above the floor.
  KeyframeId newest = -1;
  second.setKeyframeCallback([&](const KeyframeInfo& info) { newest = info.id; });
  track(&second, 10, 60, 1000);
  second.stop();
  EXPECT_GE(newest, n + 10);
}

TEST_F(SparseMapResumeTest, RestoreRefusesAnInconsistentMapOrATrackedSystem) {
  SlamSystem first(camera(), config(), vocabulary_);
  track(&first, 0, 20);
  SparseMapSnapshot bad = first.snapshot();
  first.stop();
  ASSERT_FALSE(bad.landmarks.empty());
  bad.landmarks[0].observations[0].second = 1'000'000;  // no such feature
  SlamSystem second(camera(), config(), vocabulary_);
  try {
    second.restore(bad);
    FAIL() << "restored an inconsistent map";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("out of range"), std::string::npos) << e.what();
  }
  EXPECT_EQ(second.snapshot().keyframes.size(), 0u);  // left empty
  track(&second, 0, 2);
  EXPECT_THROW(second.restore(first.snapshot()), std::invalid_argument);
  second.stop();
}

TEST_F(SparseMapResumeTest, DamagedOrMissingFilesAreRefusedAndAHalfWrittenCheckpointIgnored) {
  SlamSystem first(camera(), config(), vocabulary_);
  track(&first, 0, 40);
  const TrackerMapState saved = stateOf(first);
  first.stop();
  TrackerMapCheckpointer checkpointer(dir_.string());
  std::string error;
  ASSERT_TRUE(checkpointer.checkpoint(saved, &error).has_value()) << error;
  const fs::path chunk = dir_ / keyframeChunkFileName(3, 1);
  const fs::path index = dir_ / kTrackerMapFileName;

  // A checkpoint that crashed after its chunk and before its index: the stray chunk (of a
  // later generation) is ignored, the committed map loads, and the next checkpoint numbers
  // above it and deletes it.
  fs::copy_file(chunk, dir_ / keyframeChunkFileName(3, 7));
  ASSERT_TRUE(loadTrackerMap(dir_.string(), &error).has_value()) << error;
  const auto next = checkpointer.checkpoint(saved, &error);
  ASSERT_TRUE(next.has_value()) << error;
  EXPECT_EQ(next->generation, 8u);
  EXPECT_FALSE(fs::exists(dir_ / keyframeChunkFileName(3, 7)));

  // One flipped bit in the features: the checksum says so.
  std::string bytes;
  {
    std::ifstream in(chunk, std::ios::binary);
    bytes.assign(std::istreambuf_iterator<char>(in), {});
  }
  const std::string original = bytes;
  bytes[bytes.size() / 2] ^= 0x10;
  std::ofstream(chunk, std::ios::binary | std::ios::trunc) << bytes;
  EXPECT_FALSE(loadTrackerMap(dir_.string(), &error).has_value());
  EXPECT_NE(error.find("checksum mismatch"), std::string::npos) << error;
  std::ofstream(chunk, std::ios::binary | std::ios::trunc) << original;
  ASSERT_TRUE(loadTrackerMap(dir_.string(), &error).has_value()) << error;

  // A missing chunk is named.
  fs::rename(chunk, dir_ / "moved");
  EXPECT_FALSE(loadTrackerMap(dir_.string(), &error).has_value());
  EXPECT_NE(error.find(chunk.filename().string()), std::string::npos) << error;
  fs::rename(dir_ / "moved", chunk);

  // A truncated index.
  fs::resize_file(index, fs::file_size(index) - 3);
  EXPECT_FALSE(loadTrackerMap(dir_.string(), &error).has_value());
  EXPECT_NE(error.find("truncated"), std::string::npos) << error;
}

TEST(TrackerMapIndexTest, ForgedCountsAreRefusedBeforeAllocating) {
  TrackerMapIndex index;
  index.state.camera.intrinsics = {400, 400, 320, 240, 640, 480};
  index.state.camera.baseline_m = 0.1;
  std::string payload = encodeTrackerMapIndex(index);
  std::string error;
  ASSERT_TRUE(decodeTrackerMapIndex(payload, &error).has_value()) << error;
  // Rewrite the raw section with a chunk count of 2^32 - 1 and recompress.
  index.chunks.resize(1);
  index.chunks[0].file_name = "keyframes_e0_g1.cbkf";
  payload = encodeTrackerMapIndex(index);
  ASSERT_TRUE(decodeTrackerMapIndex(payload, &error).has_value()) << error;
  // A length claiming far more than the compressed bytes can hold.
  std::string forged = payload;
  forged[7] = 0x7f;  // uint64 length's top byte
  EXPECT_FALSE(decodeTrackerMapIndex(forged, &error).has_value());
  EXPECT_NE(error.find("out of bounds"), std::string::npos) << error;
  // Garbage instead of a zstd frame.
  forged = payload.substr(0, 8) + std::string(40, 'x');
  EXPECT_FALSE(decodeTrackerMapIndex(forged, &error).has_value());
  EXPECT_NE(error.find("decompression error"), std::string::npos) << error;
  // A chunk name that escapes the directory.
  index.chunks[0].file_name = "../etc/passwd";
  EXPECT_FALSE(decodeTrackerMapIndex(encodeTrackerMapIndex(index), &error).has_value());
  EXPECT_NE(error.find("bad or repeated chunk file name"), std::string::npos) << error;
}

TEST(PoseCodecTest, AUnitQuaternionLoadsBitIdenticalEvenWhereNormalisingWouldChangeIt) {
  // Find unit quaternions that normalising again would change in their last bits.
  std::mt19937 rng(7);
  std::normal_distribution<double> normal;
  int found = 0;
  for (int i = 0; i < 100000 && found < 20; ++i) {
    const Eigen::Quaterniond q =
        Eigen::Quaterniond(normal(rng), normal(rng), normal(rng), normal(rng)).normalized();
    if (q.coeffs() == q.normalized().coeffs()) continue;
    ++found;
    const Transformationd T = Transformationd::fromUnitQuaternion(q, Eigen::Vector3d(1, 2, 3));
    std::string bytes;
    persistence_detail::ByteWriter w(&bytes);
    persistence_detail::writePose(w, T);
    persistence_detail::ByteReader r(bytes);
    Transformationd loaded;
    ASSERT_TRUE(persistence_detail::readPose(r, &loaded));
    EXPECT_EQ(loaded.rotation().coeffs(), q.coeffs());
    EXPECT_EQ(loaded.translation(), Eigen::Vector3d(1, 2, 3));
  }
  EXPECT_GT(found, 0) << "no quaternion that normalising changes: the test proves nothing";
  // A quaternion far from unit is normalised, one beyond [0.5, 2] refused.
  for (const double scale : {1.5, 3.0}) {
    std::string bytes;
    persistence_detail::ByteWriter w(&bytes);
    for (const double v : {0.0, 0.0, 0.0, 0.0, 0.0, 0.0, scale}) w.f64(v);
    persistence_detail::ByteReader r(bytes);
    Transformationd loaded;
    EXPECT_EQ(persistence_detail::readPose(r, &loaded), scale < 2.0);
    if (scale < 2.0) {
      EXPECT_EQ(loaded.rotation().w(), 1.0);
    }
  }
}

TEST(IdLeaseTest, RoundTripAbsentAndDamaged) {
  const fs::path dir = fs::path(::testing::TempDir()) / "id_lease_test";
  fs::remove_all(dir);
  fs::create_directories(dir);
  std::string error;
  EXPECT_FALSE(readIdLease(dir.string(), &error).has_value());
  EXPECT_TRUE(error.empty()) << error;
  const IdLease lease{2, 164, 70000};
  ASSERT_TRUE(writeIdLease(dir.string(), lease, &error)) << error;
  const auto read = readIdLease(dir.string(), &error);
  ASSERT_TRUE(read.has_value()) << error;
  EXPECT_EQ(*read, lease);
  fs::resize_file(dir / kIdLeaseFileName, 40);
  EXPECT_FALSE(readIdLease(dir.string(), &error).has_value());
  EXPECT_FALSE(error.empty());
}

}  // namespace
}  // namespace cblox
