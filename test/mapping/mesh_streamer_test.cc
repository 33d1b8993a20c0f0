// The mapper's incremental mesh stream (MeshStreamer) and its receiving end (MeshMirror), on
// analytic spheres written straight into subvolume layers: what a receiver holds equals a
// full meshing of the map after every period, incremental periods send exactly the blocks a
// change can reach, poses travel without meshes, removals, the byte budget, refreshes, map
// epochs, lost messages and broken messages.

#include "core/mapping/mesh_streamer.h"

#include <atomic>
#include <set>
#include <thread>

#include <gtest/gtest.h>

#include "core/mapping/mesh_mirror.h"
#include "core/mesh/block_mesher.h"
#include "test/mesh/mesh_checks.h"

namespace cblox {
namespace {

constexpr float kVoxel = 0.05f;
constexpr int kVps = 8;
constexpr double kBlock = kVoxel * kVps;
constexpr float kTruncation = 0.15f;

Color positionColor(const Eigen::Vector3f& p) {
  const auto c = [](float v) {
    return static_cast<uint8_t>(std::clamp(128.0f + 100.0f * v, 0.0f, 255.0f));
  };
  return Color{c(p.x()), c(p.y()), c(p.z())};
}

void fillSphere(TsdfLayer* layer, const Eigen::Vector3f& centre, float radius) {
  const Eigen::Vector3f margin = Eigen::Vector3f::Constant(radius + 0.2f);
  test::fillLayer(
      layer, centre - margin, centre + margin, kTruncation,
      [&](const Eigen::Vector3f& p) { return (p - centre).norm() - radius; }, 1.0f,
      positionColor);
}

// What a receiver must hold: every block's quantised mesh, those with a surface.
std::map<SubmapId, MeshMirror::Blocks> expectedBlocks(const SubmapCollection& collection) {
  MeshConfig config;
  config.compute_normals = false;
  config.num_threads = 1;
  BlockMesher mesher(config);
  std::map<SubmapId, MeshMirror::Blocks> expected;
  for (const auto& submap : collection.submaps()) {
    const TsdfLayer& layer = submap->layer();
    for (const auto& [key, block] : layer.blocks()) {
      Mesh mesh;
      mesher.meshBlock(layer, *block, &mesh);
      if (mesh.empty()) continue;
      QuantizedBlockMesh q;
      const Eigen::Vector3d center =
          (block->index().cast<double>() + Eigen::Vector3d::Constant(0.5)) * kBlock;
      EXPECT_TRUE(quantizeBlockMesh(mesh, center, kBlock, &q, nullptr));
      expected[submap->id()][key] = q;
    }
  }
  return expected;
}

struct Stream {
  explicit Stream(MeshStreamConfig config = {}) : collection(SubmapCollectionConfig{{kVoxel, kVps}}) {
    streamer = std::make_unique<MeshStreamer>(
        config, MeshConfig{}, &collection, [this] { return epoch.load(); }, 0,
        [this](const MeshUpdate& u) { updates.push_back(u); },
        [this](const SubvolumeList& l) { lists.push_back(l); },
        [this](const std::string& line) { log.push_back(line); });
  }
  // One tick; applies what it sent to the mirror (gap-free) and returns its messages.
  std::vector<MeshUpdate> tick() {
    const size_t first = updates.size();
    streamer->tick();
    std::vector<MeshUpdate> sent(updates.begin() + static_cast<std::ptrdiff_t>(first), updates.end());
    for (const MeshUpdate& u : sent) {
      const MeshMirror::Result r = mirror.apply(u);
      EXPECT_TRUE(r.applied) << r.error;
      EXPECT_FALSE(r.gap);
    }
    if (!lists.empty()) mirror.applySubvolumes(lists.back());
    return sent;
  }
  std::shared_ptr<Submap> finishedSphere(const Eigen::Vector3f& centre, float radius,
                                         const Transformationd& T_G_S = Transformationd()) {
    auto s = collection.createSubmap(T_G_S, static_cast<KeyframeId>(collection.nextSubmapId()), 0);
    {
      Submap::WriteLock lock = s->lockForIntegration();
      fillSphere(&lock.layer(), centre, radius);
    }
    collection.finishActiveSubmap();
    return s;
  }

  std::atomic<int64_t> epoch{7};
  SubmapCollection collection;
  std::unique_ptr<MeshStreamer> streamer;
  std::vector<MeshUpdate> updates;
  std::vector<SubvolumeList> lists;
  std::vector<std::string> log;
  MeshMirror mirror;
};

std::set<uint64_t> sentKeys(const std::vector<MeshUpdate>& updates, SubmapId id) {
  std::set<uint64_t> keys;
  for (const MeshUpdate& u : updates) {
    for (const MeshBlockUpdate& b : u.blocks) {
      if (b.submap == id) keys.insert(packGridIndex(b.index));
    }
  }
  return keys;
}

TEST(QuantizedBlockMesh, RoundTripIsWithinHalfAQuantumAndClampsBeyondTheBlock) {
  const Eigen::Vector3d center(1.0, -2.0, 0.5);
  const double size = 0.32;
  Mesh mesh;
  mesh.vertices = {Eigen::Vector3f(1.1f, -2.05f, 0.5f), Eigen::Vector3f(0.85f, -1.9f, 0.61f),
                   Eigen::Vector3f(5.0f, -2.0f, 0.5f)};  // the last one far outside
  mesh.colors = {Color{1, 2, 3}, Color{4, 5, 6}, Color{7, 8, 9}};
  mesh.triangles = {Eigen::Vector3i(0, 1, 2)};
  QuantizedBlockMesh q;
  std::string error;
  ASSERT_TRUE(quantizeBlockMesh(mesh, center, size, &q, &error)) << error;
  EXPECT_EQ(q.validate(), "");
  EXPECT_EQ(q.payloadBytes(), 3u * 6 + 3u * 3 + 1u * 6);
  const Mesh back = dequantizeBlockMesh(q, center, size);
  const double half_quantum = meshQuantum(size) / 2;
  for (int v = 0; v < 2; ++v) {
    for (int a = 0; a < 3; ++a) {
      EXPECT_LE(std::abs(back.vertices[v][a] - mesh.vertices[v][a]), half_quantum + 1e-6);
    }
  }
  EXPECT_EQ(q.positions[2][0], 32767);  // clamped
  EXPECT_TRUE(back.colors == mesh.colors);
  EXPECT_TRUE(back.triangles == mesh.triangles);

  Mesh huge;
  huge.vertices.assign(QuantizedBlockMesh::kMaxVertices + 1, Eigen::Vector3f::Zero());
  EXPECT_FALSE(quantizeBlockMesh(huge, center, size, &q, &error));
  EXPECT_NE(error.find("32767"), std::string::npos) << error;
}

TEST(MeshStreamer, FirstPeriodIsARefreshOfEveryBlockWithASurface) {
  Stream s;
  s.finishedSphere(Eigen::Vector3f(0.01f, 0.02f, -0.03f), 0.5f);
  auto active = s.collection.createSubmap(Transformationd(Eigen::Quaterniond::Identity(),
                                                          Eigen::Vector3d(3, 0, 0)),
                                          1, 0);
  {
    Submap::WriteLock lock = active->lockForIntegration();
    fillSphere(&lock.layer(), Eigen::Vector3f(0.2f, 0.1f, 0.0f), 0.4f);
  }
  const std::vector<MeshUpdate> sent = s.tick();
  ASSERT_FALSE(sent.empty());
  EXPECT_TRUE(sent.front().refresh_start);
  EXPECT_EQ(sent.front().sequence, 1);
  EXPECT_EQ(sent.front().map_epoch, 7);
  EXPECT_FLOAT_EQ(sent.front().block_size, static_cast<float>(kBlock));
  EXPECT_TRUE(s.mirror.complete());
  EXPECT_EQ(s.mirror.blocks(), expectedBlocks(s.collection));
  EXPECT_GT(s.mirror.blocks().at(0).size(), 20u);
  EXPECT_GE(s.mirror.blocks().at(1).size(), 8u);

  // The subvolume list: ids, poses, active flag, bounds of the allocated blocks.
  ASSERT_EQ(s.lists.size(), 1u);
  const SubvolumeList& list = s.lists.back();
  ASSERT_EQ(list.subvolumes.size(), 2u);
  EXPECT_EQ(list.active_submap, 1);
  EXPECT_FALSE(list.subvolumes[0].active);
  EXPECT_TRUE(list.subvolumes[1].active);
  EXPECT_EQ(list.subvolumes[1].T_G_S.translation(), Eigen::Vector3d(3, 0, 0));
  EXPECT_EQ(list.subvolumes[0].num_blocks, s.collection.getSubmap(0)->numBlocks());
  // Sphere 0: blocks over [c - 0.7, c + 0.7] per axis, in 0.4 m blocks.
  const BlockIndex lo = s.collection.getSubmap(0)->layer().blockIndexFromPoint(
      Eigen::Vector3f(0.01f, 0.02f, -0.03f) - Eigen::Vector3f::Constant(0.7f));
  EXPECT_TRUE(list.subvolumes[0].min_S.isApprox((lo.cast<float>() * kBlock)));

  // The mirror's mesh in G: every vertex within 1.5 voxels of sphere 0 or of sphere 1 at
  // x + 3.
  const Mesh in_g = s.mirror.meshInG();
  ASSERT_GT(in_g.numTriangles(), 1000u);
  for (const Eigen::Vector3f& v : in_g.vertices) {
    const float d0 = std::abs((v - Eigen::Vector3f(0.01f, 0.02f, -0.03f)).norm() - 0.5f);
    const float d1 = std::abs((v - Eigen::Vector3f(3.2f, 0.1f, 0.0f)).norm() - 0.4f);
    ASSERT_LT(std::min(d0, d1), 0.01f) << v.transpose();
  }

  // Nothing changed: no mesh message, the list again.
  EXPECT_TRUE(s.tick().empty());
  EXPECT_EQ(s.lists.size(), 2u);
  EXPECT_EQ(s.streamer->stats().refreshes, 1u);
}

TEST(MeshStreamer, SendsExactlyTheChangedBlockAndItsLowerNeighbours) {
  Stream s;
  auto active = s.collection.createSubmap(Transformationd(), 0, 0);
  {
    Submap::WriteLock lock = active->lockForIntegration();
    fillSphere(&lock.layer(), Eigen::Vector3f(0.03f, 0.01f, 0.02f), 0.6f);
  }
  s.tick();
  ASSERT_TRUE(s.mirror.complete());

  // Dent one surface block: a voxel of block (1, 0, 0) flips sign.
  const BlockIndex changed(1, 0, 0);
  {
    Submap::WriteLock lock = active->lockForIntegration();
    Block* block = lock.layer().getBlock(changed);
    ASSERT_NE(block, nullptr);
    for (int i = 0; i < block->numVoxels(); ++i) {
      TsdfVoxel& v = block->voxel(i);
      if (v.weight > 0 && std::abs(v.distance) < 0.03f) v.distance = -v.distance - 0.01f;
    }
    block->setUpdated(true);
  }
  const std::vector<MeshUpdate> sent = s.tick();
  ASSERT_FALSE(sent.empty());
  EXPECT_FALSE(sent.front().refresh_start);
  EXPECT_EQ(sent.front().sequence, 2);
  std::set<uint64_t> reachable{packGridIndex(changed)};
  for (const auto& o : kMeshLowerNeighbours) {
    reachable.insert(packGridIndex(changed + BlockIndex(o[0], o[1], o[2])));
  }
  const std::set<uint64_t> keys = sentKeys(sent, active->id());
  EXPECT_TRUE(keys.count(packGridIndex(changed)));
  for (const uint64_t key : keys) EXPECT_TRUE(reachable.count(key));
  EXPECT_EQ(s.mirror.blocks(), expectedBlocks(s.collection));
  EXPECT_TRUE(s.mirror.complete());
}

TEST(MeshStreamer, APoseChangeMovesTheMeshWithoutResendingIt) {
  Stream s;
  auto sub = s.finishedSphere(Eigen::Vector3f::Zero(), 0.5f);
  s.tick();
  const Mesh before = s.mirror.meshInG();
  const Transformationd moved(Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ())),
                              Eigen::Vector3d(1.0, -2.0, 0.5));
  ASSERT_TRUE(sub->setT_G_M(moved));
  EXPECT_TRUE(s.tick().empty());  // no mesh bytes
  EXPECT_TRUE(s.lists.back().subvolumes[0].T_G_S.translation().isApprox(moved.translation()));
  const Mesh after = s.mirror.meshInG();
  ASSERT_EQ(after.numVertices(), before.numVertices());
  const Transformation T = moved.cast<float>();
  for (size_t v = 0; v < after.numVertices(); ++v) {
    ASSERT_LT((after.vertices[v] - T * before.vertices[v]).norm(), 1e-5f);
  }
}

TEST(MeshStreamer, RemovedBlocksAndSubvolumesAreSentAsRemovals) {
  Stream s;
  auto first = s.finishedSphere(Eigen::Vector3f::Zero(), 0.5f);
  s.finishedSphere(Eigen::Vector3f(0.1f, 0.0f, 0.0f), 0.3f);
  s.tick();
  // A block with a surface leaves the finished layer (as a fusion or the memory cap would).
  const auto& held = s.mirror.blocks().at(0);
  const BlockIndex gone = unpackGridIndex(held.begin()->first);
  ASSERT_TRUE(first->mutableLayer()->removeBlock(gone));
  std::vector<MeshUpdate> sent = s.tick();
  ASSERT_FALSE(sent.empty());
  bool removal = false;
  for (const MeshBlockUpdate& b : sent.front().blocks) {
    if (b.submap == 0 && b.index == gone) removal = b.mesh.empty();
  }
  EXPECT_TRUE(removal);
  EXPECT_EQ(s.mirror.blocks(), expectedBlocks(s.collection));

  ASSERT_TRUE(s.collection.removeSubmap(0));
  sent = s.tick();
  ASSERT_EQ(sent.size(), 1u);
  EXPECT_EQ(sent.front().removed_submaps, std::vector<SubmapId>{0});
  EXPECT_TRUE(sent.front().blocks.empty());
  EXPECT_EQ(s.mirror.blocks().count(0), 0u);
  EXPECT_EQ(s.mirror.blocks(), expectedBlocks(s.collection));
  EXPECT_EQ(s.lists.back().subvolumes.size(), 1u);
}

TEST(MeshStreamer, TheBudgetSpreadsAPeriodOverSeveralWithPendingCounts) {
  MeshStreamConfig config;
  config.max_message_bytes = 4096;
  config.max_bytes_per_period = 8192;
  Stream s(config);
  s.finishedSphere(Eigen::Vector3f::Zero(), 0.6f);
  std::vector<size_t> pending;
  for (int period = 0; period < 200; ++period) {
    const std::vector<MeshUpdate> sent = s.tick();
    ASSERT_FALSE(sent.empty());
    size_t period_bytes = 0;
    for (const MeshUpdate& u : sent) {
      size_t largest = 0;
      for (const auto& b : u.blocks) largest = std::max(largest, b.mesh.payloadBytes());
      EXPECT_TRUE(u.blocks.size() == 1 || u.payloadBytes() <= config.max_message_bytes);
      period_bytes += u.payloadBytes();
      pending.push_back(u.blocks_pending);
    }
    EXPECT_LE(period_bytes, config.max_bytes_per_period + 4096);
    if (sent.back().blocks_pending == 0) break;
    EXPECT_FALSE(s.mirror.complete());
  }
  EXPECT_GT(pending.size(), 4u);
  for (size_t i = 1; i < pending.size(); ++i) EXPECT_LT(pending[i], pending[i - 1]);
  EXPECT_EQ(pending.back(), 0u);
  EXPECT_TRUE(s.mirror.complete());
  EXPECT_EQ(s.mirror.blocks(), expectedBlocks(s.collection));
}

TEST(MeshStreamer, ARefreshResendsEveryBlockAndHealsALostMessage) {
  Stream s;
  s.finishedSphere(Eigen::Vector3f::Zero(), 0.5f);
  auto active = s.collection.createSubmap(Transformationd(), 1, 0);
  {
    Submap::WriteLock lock = active->lockForIntegration();
    fillSphere(&lock.layer(), Eigen::Vector3f(0.0f, 0.0f, 0.1f), 0.3f);
  }
  s.tick();
  // A message the mirror never sees.
  {
    Submap::WriteLock lock = active->lockForIntegration();
    fillSphere(&lock.layer(), Eigen::Vector3f(0.0f, 0.0f, 0.1f), 0.35f);
  }
  s.streamer->tick();
  ASSERT_FALSE(s.updates.empty());
  const int64_t lost = s.updates.back().sequence;
  // The next change arrives: the mirror sees the gap.
  {
    Submap::WriteLock lock = active->lockForIntegration();
    fillSphere(&lock.layer(), Eigen::Vector3f(0.0f, 0.0f, 0.1f), 0.25f);
  }
  const size_t before = s.updates.size();
  s.streamer->tick();
  ASSERT_GT(s.updates.size(), before);
  EXPECT_EQ(s.updates[before].sequence, lost + 1);
  const MeshMirror::Result r = s.mirror.apply(s.updates[before]);
  EXPECT_TRUE(r.applied);
  EXPECT_TRUE(r.gap);
  EXPECT_FALSE(s.mirror.complete());

  s.streamer->requestRefresh();
  const std::vector<MeshUpdate> sent = s.tick();
  ASSERT_FALSE(sent.empty());
  EXPECT_TRUE(sent.front().refresh_start);
  EXPECT_TRUE(s.mirror.complete());
  const auto expected = expectedBlocks(s.collection);
  EXPECT_EQ(s.mirror.blocks(), expected);
  size_t expected_count = 0;
  for (const auto& [id, blocks] : expected) expected_count += blocks.size();
  size_t sent_count = 0;
  for (const MeshUpdate& u : sent) sent_count += u.blocks.size();
  EXPECT_EQ(sent_count, expected_count);
  EXPECT_EQ(s.streamer->stats().refreshes, 2u);
}

TEST(MeshStreamer, ANewMapEpochBeginsARefresh) {
  Stream s;
  s.finishedSphere(Eigen::Vector3f::Zero(), 0.5f);
  s.tick();
  s.epoch = 8;
  const std::vector<MeshUpdate> sent = s.tick();
  ASSERT_FALSE(sent.empty());
  EXPECT_TRUE(sent.front().refresh_start);
  EXPECT_EQ(sent.front().map_epoch, 8);
  EXPECT_EQ(s.lists.back().map_epoch, 8);
  EXPECT_EQ(s.mirror.mapEpoch(), 8);
  EXPECT_EQ(s.mirror.blocks(), expectedBlocks(s.collection));
}

TEST(MeshStreamer, ConcurrentIntegrationThenAQuietPeriodLeavesTheMirrorExact) {
  Stream s;
  s.streamer->start();  // the copy thread takes the layer lock, as in the mapper
  auto active = s.collection.createSubmap(Transformationd(), 0, 0);
  std::atomic<bool> stop{false};
  std::thread writer([&] {
    for (int i = 0; !stop.load(); ++i) {
      {
        Submap::WriteLock lock = active->lockForIntegration();
        fillSphere(&lock.layer(), Eigen::Vector3f(0.01f * (i % 7), 0.0f, 0.0f),
                   0.3f + 0.01f * (i % 5));
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(1));  // frames come and go
    }
  });
  for (int period = 0; period < 8; ++period) {
    s.tick();
    std::this_thread::sleep_for(std::chrono::milliseconds(3));
  }
  stop = true;
  writer.join();
  s.tick();
  s.streamer->stop();
  EXPECT_TRUE(s.mirror.complete());
  EXPECT_EQ(s.mirror.blocks(), expectedBlocks(s.collection));
}

TEST(MeshMirror, RefusesBrokenMessagesWholeAndKeepsItsState) {
  Stream s;
  s.finishedSphere(Eigen::Vector3f::Zero(), 0.5f);
  s.tick();
  const auto held = s.mirror.blocks();
  MeshUpdate bad;
  bad.map_epoch = 7;
  bad.sequence = s.mirror.lastSequence() + 1;
  bad.block_size = static_cast<float>(kBlock);
  MeshBlockUpdate good_block{0, BlockIndex(50, 0, 0), {}};
  good_block.mesh.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  good_block.mesh.triangles = {{0, 1, 2}};
  MeshBlockUpdate broken = good_block;
  broken.mesh.triangles = {{0, 1, 3}};
  bad.blocks = {good_block, broken};
  MeshMirror::Result r = s.mirror.apply(bad);
  EXPECT_FALSE(r.applied);
  EXPECT_NE(r.error.find("names vertex 3"), std::string::npos) << r.error;
  broken = good_block;
  broken.mesh.colors = {{1, 2, 3}};
  bad.blocks = {broken};
  r = s.mirror.apply(bad);
  EXPECT_FALSE(r.applied);
  EXPECT_NE(r.error.find("colours"), std::string::npos) << r.error;
  bad.blocks = {good_block};
  bad.block_size = std::numeric_limits<float>::quiet_NaN();
  EXPECT_FALSE(s.mirror.apply(bad).applied);
  bad.block_size = static_cast<float>(kBlock);
  bad.blocks[0].index = BlockIndex(kGridIndexMax + 1, 0, 0);
  EXPECT_FALSE(s.mirror.apply(bad).applied);
  EXPECT_EQ(s.mirror.blocks(), held);
  EXPECT_TRUE(s.mirror.complete());
}

TEST(MeshStreamConfig, RefusesOutOfRangeSettings) {
  MeshStreamConfig c;
  EXPECT_EQ(c.validate(), "");
  c.period_s = 0.0;
  EXPECT_NE(c.validate().find("period_s"), std::string::npos);
  c = {};
  c.max_message_bytes = 100;
  EXPECT_NE(c.validate().find("max_message_bytes"), std::string::npos);
  c = {};
  c.max_bytes_per_period = c.max_message_bytes - 1;
  EXPECT_NE(c.validate().find("max_bytes_per_period"), std::string::npos);
  c = {};
  c.refresh_period_s = 0.5;
  EXPECT_NE(c.validate().find("refresh_period_s"), std::string::npos);
}

}  // namespace
}  // namespace cblox
