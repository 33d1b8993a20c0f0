// The mesh stream's LCM messages: a MeshUpdate and a SubvolumeList survive encode, LCM's wire
// and decode unchanged; messages whose counts, indices, meshes or poses are broken are
// refused naming the field.

#include "daemon/common/mesh_stream_codec.h"

#include <cmath>
#include <vector>

#include <gtest/gtest.h>

namespace cblox {
namespace {

template <typename T>
T throughTheWire(const T& msg) {
  std::vector<uint8_t> bytes(static_cast<size_t>(msg.getEncodedSize()));
  EXPECT_EQ(msg.encode(bytes.data(), 0, static_cast<int>(bytes.size())),
            static_cast<int>(bytes.size()));
  T out;
  EXPECT_EQ(out.decode(bytes.data(), 0, static_cast<int>(bytes.size())),
            static_cast<int>(bytes.size()));
  return out;
}

MeshUpdate sampleUpdate() {
  MeshUpdate u;
  u.map_epoch = 1234567;
  u.sequence = 9;
  u.refresh_start = true;
  u.blocks_pending = 3;
  u.block_size = 0.32f;
  u.removed_submaps = {2, 4};
  MeshBlockUpdate a{5, BlockIndex(-3, 0, 7), {}};
  a.mesh.positions = {{-32767, 0, 32767}, {1, 2, 3}, {-4, -5, -6}, {7, 8, 9}};
  a.mesh.colors = {{255, 0, 0}, {0, 255, 0}, {0, 0, 255}, {1, 2, 3}};
  a.mesh.triangles = {{0, 1, 2}, {2, 1, 3}};
  MeshBlockUpdate removal{6, BlockIndex(1, 1, 1), {}};
  MeshBlockUpdate plain = a;  // no colours
  plain.index = BlockIndex(0, 0, 0);
  plain.mesh.colors.clear();
  u.blocks = {a, removal, plain};
  return u;
}

TEST(MeshStreamCodec, AnUpdateSurvivesTheWireUnchanged) {
  const MeshUpdate u = sampleUpdate();
  const mesh_update_t msg = throughTheWire(encodeMeshUpdate(u, 42));
  EXPECT_EQ(msg.utime, 42);
  MeshUpdate back;
  std::string error;
  ASSERT_TRUE(decodeMeshUpdate(msg, &back, &error)) << error;
  EXPECT_EQ(back.map_epoch, u.map_epoch);
  EXPECT_EQ(back.sequence, u.sequence);
  EXPECT_EQ(back.refresh_start, u.refresh_start);
  EXPECT_EQ(back.blocks_pending, u.blocks_pending);
  EXPECT_EQ(back.block_size, u.block_size);
  EXPECT_EQ(back.removed_submaps, u.removed_submaps);
  ASSERT_EQ(back.blocks.size(), u.blocks.size());
  for (size_t i = 0; i < u.blocks.size(); ++i) {
    EXPECT_EQ(back.blocks[i].submap, u.blocks[i].submap);
    EXPECT_EQ(back.blocks[i].index, u.blocks[i].index);
    EXPECT_EQ(back.blocks[i].mesh, u.blocks[i].mesh);
  }
}

TEST(MeshStreamCodec, BrokenUpdatesAreRefusedNamingTheField) {
  const mesh_update_t good = encodeMeshUpdate(sampleUpdate(), 1);
  MeshUpdate out;
  std::string error;
  struct Case {
    void (*breakIt)(mesh_update_t*);
    const char* field;
  };
  const Case cases[] = {
      {[](mesh_update_t* m) { m->num_blocks = 7; }, "num_blocks"},
      {[](mesh_update_t* m) { m->num_removed = -1; }, "num_removed"},
      {[](mesh_update_t* m) { m->blocks_pending = -2; }, "blocks_pending"},
      {[](mesh_update_t* m) { m->blocks[0].num_vertices = 3; }, "blocks[0].num_vertices"},
      {[](mesh_update_t* m) { m->blocks[0].num_colors = 1; }, "blocks[0].num_colors"},
      {[](mesh_update_t* m) { m->blocks[2].num_triangles = 0; }, "blocks[2].num_triangles"},
      {[](mesh_update_t* m) { m->blocks[0].triangle[1][2] = 4; }, "names vertex 4"},
      {[](mesh_update_t* m) { m->blocks[0].triangle[0][0] = -1; }, "names vertex -1"},
      {[](mesh_update_t* m) {
         m->blocks[0].color.pop_back();
         m->blocks[0].num_colors = 3;
       },
       "colours for 4 vertices"},
      {[](mesh_update_t* m) { m->blocks[1].index[2] = 1 << 21; }, "blocks[1].index"},
  };
  for (const Case& c : cases) {
    mesh_update_t bad = good;
    c.breakIt(&bad);
    error.clear();
    EXPECT_FALSE(decodeMeshUpdate(bad, &out, &error)) << c.field;
    EXPECT_NE(error.find(c.field), std::string::npos) << error;
  }
}

TEST(MeshStreamCodec, ASubvolumeListSurvivesTheWireAndBadOnesAreRefused) {
  SubvolumeList list;
  list.map_epoch = 77;
  list.active_submap = 3;
  list.block_size = 0.16f;
  SubvolumeView a;
  a.id = 2;
  a.T_G_S = Transformationd(Eigen::Quaterniond(Eigen::AngleAxisd(0.5, Eigen::Vector3d::UnitY())),
                            Eigen::Vector3d(1, -2, 3));
  a.anchor_keyframe = 17;
  a.num_blocks = 250;
  a.min_S = Eigen::Vector3f(-1.6f, -0.32f, 0.0f);
  a.max_S = Eigen::Vector3f(3.2f, 1.6f, 0.96f);
  SubvolumeView b;
  b.id = 3;
  b.active = true;
  list.subvolumes = {a, b};
  const subvolume_list_t msg = throughTheWire(encodeSubvolumeList(list, 5));
  SubvolumeList back;
  std::string error;
  ASSERT_TRUE(decodeSubvolumeList(msg, &back, &error)) << error;
  EXPECT_EQ(back.map_epoch, 77);
  EXPECT_EQ(back.active_submap, 3);
  EXPECT_EQ(back.block_size, 0.16f);
  ASSERT_EQ(back.subvolumes.size(), 2u);
  EXPECT_EQ(back.subvolumes[0].id, 2);
  EXPECT_FALSE(back.subvolumes[0].active);
  EXPECT_TRUE(back.subvolumes[1].active);
  EXPECT_TRUE(back.subvolumes[0].T_G_S.translation().isApprox(a.T_G_S.translation()));
  EXPECT_TRUE(back.subvolumes[0].T_G_S.rotation().isApprox(a.T_G_S.rotation(), 1e-12));
  EXPECT_EQ(back.subvolumes[0].anchor_keyframe, 17);
  EXPECT_EQ(back.subvolumes[0].num_blocks, 250u);
  EXPECT_EQ(back.subvolumes[0].min_S, a.min_S);
  EXPECT_EQ(back.subvolumes[0].max_S, a.max_S);

  subvolume_list_t bad = msg;
  bad.num_subvolumes = 3;
  EXPECT_FALSE(decodeSubvolumeList(bad, &back, &error));
  EXPECT_NE(error.find("subvolume_ids"), std::string::npos) << error;
  bad = msg;
  bad.poses[1].orientation[0] = 2.0;  // not a unit quaternion
  EXPECT_FALSE(decodeSubvolumeList(bad, &back, &error));
  EXPECT_NE(error.find("poses[1]"), std::string::npos) << error;
  bad = msg;
  bad.bounds_max[0][1] = std::nanf("");
  EXPECT_FALSE(decodeSubvolumeList(bad, &back, &error));
  EXPECT_NE(error.find("not finite"), std::string::npos) << error;
}

}  // namespace
}  // namespace cblox
