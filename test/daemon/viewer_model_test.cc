// cblox-viewer's model: what a browser is sent (the state first, then mesh blocks in the
// documented binary layout, then trajectory, keyframes, events, health), that a slow browser
// gets the newest state of each block once (never a backlog), message size bounds, full
// resends after a refresh, and the events loop closures and fusions make.

#include "daemon/viewer/viewer_model.h"

#include <cstring>
#include <map>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

namespace cblox {
namespace {

using Json = nlohmann::json;

// The binary mesh message, parsed as viewer_model.h documents it.
struct ParsedBlock {
  double subvolume = 0;
  int32_t index[3] = {0, 0, 0};
  std::vector<int16_t> positions;
  std::vector<uint8_t> colors;
  std::vector<uint16_t> triangles;
};
struct ParsedMesh {
  uint32_t flags = 0;
  float block_size = 0;
  std::vector<double> removed;
  std::vector<ParsedBlock> blocks;
};

template <typename T>
T take(const std::string& data, size_t* o) {
  T v;
  EXPECT_LE(*o + sizeof(T), data.size());
  std::memcpy(&v, data.data() + *o, sizeof(T));
  *o += sizeof(T);
  return v;
}

ParsedMesh parse(const std::string& data) {
  ParsedMesh m;
  size_t o = 0;
  EXPECT_EQ(take<uint32_t>(data, &o), 1u);
  m.flags = take<uint32_t>(data, &o);
  m.block_size = take<float>(data, &o);
  const uint32_t removed = take<uint32_t>(data, &o), blocks = take<uint32_t>(data, &o);
  for (uint32_t i = 0; i < removed; ++i) m.removed.push_back(take<double>(data, &o));
  const auto pad = [&] { o = (o + 3) / 4 * 4; };
  for (uint32_t b = 0; b < blocks; ++b) {
    ParsedBlock p;
    p.subvolume = take<double>(data, &o);
    for (int a = 0; a < 3; ++a) p.index[a] = take<int32_t>(data, &o);
    const uint32_t nv = take<uint32_t>(data, &o), nt = take<uint32_t>(data, &o);
    const bool color = take<uint32_t>(data, &o) != 0;
    for (uint32_t k = 0; k < 3 * nv; ++k) p.positions.push_back(take<int16_t>(data, &o));
    pad();
    if (color) {
      for (uint32_t k = 0; k < 3 * nv; ++k) p.colors.push_back(take<uint8_t>(data, &o));
      pad();
    }
    for (uint32_t k = 0; k < 3 * nt; ++k) p.triangles.push_back(take<uint16_t>(data, &o));
    pad();
    m.blocks.push_back(std::move(p));
  }
  EXPECT_EQ(o, data.size());
  return m;
}

QuantizedBlockMesh triangle(int16_t offset, bool color = true) {
  QuantizedBlockMesh q;
  q.positions = {{offset, 0, 0}, {1000, offset, 0}, {0, 1000, -5}};
  if (color) q.colors = {{10, 20, 30}, {40, 50, 60}, {70, 80, 90}};
  q.triangles = {{0, 1, 2}};
  return q;
}

MeshUpdate update(int64_t sequence, bool refresh, std::vector<MeshBlockUpdate> blocks,
                  std::vector<SubmapId> removed = {}) {
  MeshUpdate u;
  u.map_epoch = 5;
  u.sequence = sequence;
  u.refresh_start = refresh;
  u.block_size = 0.32f;
  u.blocks = std::move(blocks);
  u.removed_submaps = std::move(removed);
  return u;
}

SubvolumeList listOf(std::vector<SubmapId> ids) {
  SubvolumeList l;
  l.map_epoch = 5;
  l.block_size = 0.32f;
  for (const SubmapId id : ids) {
    SubvolumeView v;
    v.id = id;
    v.T_G_S = Transformationd(Eigen::Quaterniond::Identity(), Eigen::Vector3d(id, 0, 0));
    l.subvolumes.push_back(v);
  }
  return l;
}

// Every message pending for `client`, in order.
std::vector<BrowserMessage> drain(ViewerModel* model, int client, size_t max_bytes = 1 << 20) {
  std::vector<BrowserMessage> out;
  BrowserMessage m;
  while (model->nextMessage(client, max_bytes, &m)) out.push_back(m);
  return out;
}

std::vector<ParsedMesh> meshes(const std::vector<BrowserMessage>& messages) {
  std::vector<ParsedMesh> out;
  for (const BrowserMessage& m : messages) {
    if (m.binary) out.push_back(parse(m.data));
  }
  return out;
}

std::vector<Json> jsons(const std::vector<BrowserMessage>& messages, const std::string& type) {
  std::vector<Json> out;
  for (const BrowserMessage& m : messages) {
    if (m.binary) continue;
    Json j = Json::parse(m.data);
    if (j["type"] == type) out.push_back(j);
  }
  return out;
}

TEST(ViewerModel, ANewBrowserGetsTheStateThenEveryBlockInTheDocumentedLayout) {
  ViewerModel model({});
  model.applySubvolumes(listOf({0, 1}), 0);
  ASSERT_TRUE(model.applyMeshUpdate(update(1, true,
                                           {{0, BlockIndex(1, -2, 3), triangle(7)},
                                            {1, BlockIndex(0, 0, 0), triangle(-9, false)}}))
                  .applied);
  EXPECT_TRUE(model.meshComplete());
  const int client = model.addClient();
  const std::vector<BrowserMessage> sent = drain(&model, client);
  ASSERT_GE(sent.size(), 2u);
  EXPECT_FALSE(sent[0].binary);
  const Json state = Json::parse(sent[0].data);
  EXPECT_EQ(state["type"], "state");
  EXPECT_EQ(state["complete"], true);
  ASSERT_EQ(state["subvolumes"].size(), 2u);
  EXPECT_EQ(state["subvolumes"][1]["id"], 1);
  EXPECT_EQ(state["subvolumes"][1]["mesh_blocks"], 1);
  EXPECT_DOUBLE_EQ(state["subvolumes"][1]["pose"][12].get<double>(), 1.0);  // column-major x
  ASSERT_TRUE(sent[1].binary);
  const ParsedMesh m = parse(sent[1].data);
  EXPECT_EQ(m.flags, 1u);  // drop everything first
  EXPECT_FLOAT_EQ(m.block_size, 0.32f);
  ASSERT_EQ(m.blocks.size(), 2u);
  EXPECT_EQ(m.blocks[0].subvolume, 0.0);
  EXPECT_EQ(m.blocks[0].index[1], -2);
  EXPECT_EQ(m.blocks[0].positions, (std::vector<int16_t>{7, 0, 0, 1000, 7, 0, 0, 1000, -5}));
  EXPECT_EQ(m.blocks[0].colors, (std::vector<uint8_t>{10, 20, 30, 40, 50, 60, 70, 80, 90}));
  EXPECT_EQ(m.blocks[0].triangles, (std::vector<uint16_t>{0, 1, 2}));
  EXPECT_TRUE(m.blocks[1].colors.empty());
  EXPECT_FALSE(model.waitForWork(client, std::chrono::milliseconds(1)));
}

TEST(ViewerModel, ASlowBrowserGetsTheNewestMeshOfEachBlockOnce) {
  ViewerModel model({});
  model.applySubvolumes(listOf({0}), 0);
  model.applyMeshUpdate(update(1, true, {{0, BlockIndex(0, 0, 0), triangle(1)}}));
  const int client = model.addClient();
  drain(&model, client);
  // Five updates of one block and a removal of another while the browser reads nothing.
  for (int16_t i = 2; i <= 6; ++i) {
    ASSERT_TRUE(model.applyMeshUpdate(update(i, false, {{0, BlockIndex(0, 0, 0), triangle(i)},
                                                        {0, BlockIndex(5, 0, 0), triangle(i)}}))
                    .applied);
  }
  model.applyMeshUpdate(update(7, false, {{0, BlockIndex(5, 0, 0), {}}}));
  ASSERT_TRUE(model.waitForWork(client, std::chrono::milliseconds(1)));
  const std::vector<ParsedMesh> m = meshes(drain(&model, client));
  ASSERT_EQ(m.size(), 1u);
  EXPECT_EQ(m[0].flags, 0u);
  ASSERT_EQ(m[0].blocks.size(), 2u);
  EXPECT_EQ(m[0].blocks[0].positions[0], 6);        // the newest
  EXPECT_TRUE(m[0].blocks[1].positions.empty());    // block (5, 0, 0): removed
}

TEST(ViewerModel, MeshMessagesStayWithinTheirSizeAndARefreshResendsEverything) {
  ViewerModel model({});
  model.applySubvolumes(listOf({0, 1}), 0);
  std::vector<MeshBlockUpdate> blocks;
  for (int i = 0; i < 40; ++i) blocks.push_back({i % 2, BlockIndex(i, 0, 0), triangle(static_cast<int16_t>(i))});
  model.applyMeshUpdate(update(1, true, blocks));
  const int client = model.addClient();
  const std::vector<BrowserMessage> sent = drain(&model, client, 300);
  size_t total = 0;
  for (const BrowserMessage& m : sent) {
    if (!m.binary) continue;
    const ParsedMesh p = parse(m.data);
    total += p.blocks.size();
    EXPECT_LE(p.blocks.size(), 3u);  // 300 bytes: a 44 + 20 + 12 + 8 = 84-byte block each
  }
  EXPECT_EQ(total, 40u);

  // Subvolume 1 removed: one message names it; a refresh then resends everything with the
  // drop-everything flag.
  model.applyMeshUpdate(update(2, false, {}, {1}));
  std::vector<ParsedMesh> m = meshes(drain(&model, client));
  ASSERT_EQ(m.size(), 1u);
  EXPECT_EQ(m[0].removed, std::vector<double>{1.0});
  model.applyMeshUpdate(update(3, true, {{0, BlockIndex(0, 0, 0), triangle(3)}}));
  m = meshes(drain(&model, client));
  ASSERT_EQ(m.size(), 1u);
  EXPECT_EQ(m[0].flags, 1u);
  EXPECT_EQ(m[0].blocks.size(), 1u);
}

TEST(ViewerModel, LoopClosuresFusionsAndGapsAreEventsAndState) {
  ViewerModel model({});
  const int client = model.addClient();
  model.addKeyframe(3, Transformationd(Eigen::Quaterniond::Identity(), Eigen::Vector3d(1, 0, 0)));
  model.moveKeyframes({{3, Transformationd(Eigen::Quaterniond::Identity(), Eigen::Vector3d(1.5, 0, 0))}},
                      true, 100);
  model.setFusedCount(0, 50);
  model.setFusedCount(2, 200);
  model.applySubvolumes(listOf({0, 1, 2}), 10);
  model.applySubvolumes(listOf({0, 2}), 300);
  const std::vector<BrowserMessage> sent = drain(&model, client);
  const std::vector<Json> events = jsons(sent, "events");
  ASSERT_FALSE(events.empty());
  std::vector<std::string> texts;
  for (const Json& e : events) {
    for (const Json& x : e["events"]) texts.push_back(x["kind"].get<std::string>() + ": " + x["text"].get<std::string>());
  }
  ASSERT_EQ(texts.size(), 3u);
  EXPECT_EQ(texts[0], "loop: loop closure: 1 keyframes corrected, up to 0.50 m");
  EXPECT_EQ(texts[1], "fusion: 2 subvolume(s) fused (2 since the mapper started)");
  EXPECT_EQ(texts[2], "fusion: subvolume 1 left the map (fused)");
  const std::vector<Json> keyframes = jsons(sent, "keyframes");
  ASSERT_FALSE(keyframes.empty());
  EXPECT_EQ(keyframes.back()["points"], Json::array({1.5, 0.0, 0.0}));

  // A lost message: the mirror is out of sync until a refresh.
  model.applyMeshUpdate(update(1, true, {}));
  EXPECT_TRUE(model.meshSynced());
  EXPECT_TRUE(model.applyMeshUpdate(update(3, false, {})).gap);
  EXPECT_FALSE(model.meshSynced());
}

TEST(ViewerModel, TheTrajectoryIsThinnedAndTheTrackerWinsOverGroundTruth) {
  ViewerModel::Settings settings;
  settings.max_trajectory_points = 100;
  ViewerModel model(settings);
  const int client = model.addClient();
  const auto at = [](double x) {
    return Transformationd(Eigen::Quaterniond::Identity(), Eigen::Vector3d(x, 0, 0));
  };
  for (int i = 0; i < 120; ++i) model.addVehiclePose(i * 200000, at(i), false, 0);
  std::vector<Json> t = jsons(drain(&model, client), "trajectory");
  ASSERT_FALSE(t.empty());
  EXPECT_TRUE(t.back()["reset"].get<bool>());
  const size_t points = t.back()["points"].size() / 3;
  EXPECT_LE(points, 100u);
  EXPECT_GE(points, 50u);
  // Poses closer than 0.1 s apart only move the vehicle.
  model.addVehiclePose(150 * 200000, at(150), false, 0);  // 71 points: no thinning
  model.addVehiclePose(150 * 200000 + 50000, at(151), false, 0);
  t = jsons(drain(&model, client), "trajectory");
  ASSERT_EQ(t.size(), 1u);
  EXPECT_FALSE(t[0]["reset"].get<bool>());
  EXPECT_EQ(t[0]["points"].size(), 3u);
  // The tracker's first pose starts a new trajectory; ground truth is ignored from then on.
  model.addVehiclePose(200 * 200000, at(-1), true, 0);
  model.addVehiclePose(201 * 200000, at(99), false, 0);
  const std::vector<BrowserMessage> sent = drain(&model, client);
  t = jsons(sent, "trajectory");
  ASSERT_EQ(t.size(), 1u);
  EXPECT_TRUE(t[0]["reset"].get<bool>());
  EXPECT_EQ(t[0]["points"], Json::array({-1.0, 0.0, 0.0}));
  const std::vector<Json> vehicle = jsons(sent, "vehicle");
  ASSERT_EQ(vehicle.size(), 1u);
  EXPECT_DOUBLE_EQ(vehicle[0]["pose"][12].get<double>(), -1.0);
}

TEST(ViewerModel, ExportResultsAndHealthReachTheBrowser) {
  ViewerModel model({});
  const int client = model.addClient();
  drain(&model, client);
  model.setHeartbeat(ProcessHealth{"cblox-mapper", 42, "running", 7, {{"frames_integrated", 9}}});
  model.setExportResult(3, true, "wrote it", "/maps/viewer_export_3.ply");
  const std::vector<BrowserMessage> sent = drain(&model, client);
  const std::vector<Json> health = jsons(sent, "health");
  ASSERT_EQ(health.size(), 1u);
  EXPECT_EQ(health[0]["processes"][0]["counters"]["frames_integrated"], 9);
  const std::vector<Json> exports = jsons(sent, "export");
  ASSERT_EQ(exports.size(), 1u);
  EXPECT_EQ(exports[0]["url"], "/export/3.ply");
  EXPECT_EQ(model.exportFile(3), "/maps/viewer_export_3.ply");
  EXPECT_EQ(model.exportFile(4), "");
  model.setExportResult(4, false, "disk full", "");
  EXPECT_EQ(model.exportFile(4), "");
}

}  // namespace
}  // namespace cblox
