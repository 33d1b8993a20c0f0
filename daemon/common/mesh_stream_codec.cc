#include "daemon/common/mesh_stream_codec.h"

#include <cmath>
#include <optional>

#include "daemon/common/lcm_messages.h"

namespace cblox {

mesh_update_t encodeMeshUpdate(const MeshUpdate& update, int64_t utime) {
  mesh_update_t msg;
  msg.utime = utime;
  msg.map_epoch = update.map_epoch;
  msg.sequence = update.sequence;
  msg.refresh_start = update.refresh_start;
  msg.blocks_pending = static_cast<int32_t>(std::min<size_t>(update.blocks_pending, INT32_MAX));
  msg.block_size = update.block_size;
  msg.removed_subvolume_ids.assign(update.removed_submaps.begin(), update.removed_submaps.end());
  msg.num_removed = static_cast<int32_t>(msg.removed_subvolume_ids.size());
  msg.blocks.reserve(update.blocks.size());
  for (const MeshBlockUpdate& b : update.blocks) {
    mesh_block_t block;
    block.subvolume_id = b.submap;
    for (int a = 0; a < 3; ++a) block.index[a] = b.index[a];
    block.num_vertices = static_cast<int32_t>(b.mesh.positions.size());
    block.position.reserve(b.mesh.positions.size());
    for (const auto& p : b.mesh.positions) block.position.push_back({p[0], p[1], p[2]});
    block.num_colors = static_cast<int32_t>(b.mesh.colors.size());
    block.color.reserve(b.mesh.colors.size());
    for (const auto& c : b.mesh.colors) block.color.push_back({c[0], c[1], c[2]});
    block.num_triangles = static_cast<int32_t>(b.mesh.triangles.size());
    block.triangle.reserve(b.mesh.triangles.size());
    for (const auto& t : b.mesh.triangles) block.triangle.push_back({t[0], t[1], t[2]});
    msg.blocks.push_back(std::move(block));
  }
  msg.num_blocks = static_cast<int32_t>(msg.blocks.size());
  return msg;
}

namespace {

template <typename Array>
bool countMatches(int32_t count, const Array& array, const std::string& what, std::string* error) {
  if (count >= 0 && static_cast<size_t>(count) == array.size()) return true;
  if (error) {
    *error = what + ": count " + std::to_string(count) + " for " + std::to_string(array.size()) +
             " entries";
  }
  return false;
}

}  // namespace

bool decodeMeshUpdate(const mesh_update_t& msg, MeshUpdate* update, std::string* error) {
  if (!countMatches(msg.num_removed, msg.removed_subvolume_ids, "num_removed", error) ||
      !countMatches(msg.num_blocks, msg.blocks, "num_blocks", error)) {
    return false;
  }
  if (msg.blocks_pending < 0) {
    if (error) *error = "blocks_pending is negative";
    return false;
  }
  update->map_epoch = msg.map_epoch;
  update->sequence = msg.sequence;
  update->refresh_start = msg.refresh_start;
  update->blocks_pending = static_cast<size_t>(msg.blocks_pending);
  update->block_size = msg.block_size;
  update->removed_submaps.assign(msg.removed_subvolume_ids.begin(), msg.removed_subvolume_ids.end());
  update->blocks.clear();
  update->blocks.reserve(msg.blocks.size());
  for (size_t i = 0; i < msg.blocks.size(); ++i) {
    const mesh_block_t& block = msg.blocks[i];
    const std::string what = "blocks[" + std::to_string(i) + "]";
    if (!countMatches(block.num_vertices, block.position, what + ".num_vertices", error) ||
        !countMatches(block.num_colors, block.color, what + ".num_colors", error) ||
        !countMatches(block.num_triangles, block.triangle, what + ".num_triangles", error)) {
      return false;
    }
    MeshBlockUpdate b;
    b.submap = block.subvolume_id;
    b.index = BlockIndex(block.index[0], block.index[1], block.index[2]);
    if (!gridIndexInRange(b.index)) {
      if (error) *error = what + ".index out of range";
      return false;
    }
    b.mesh.positions.reserve(block.position.size());
    for (const auto& p : block.position) b.mesh.positions.push_back({p[0], p[1], p[2]});
    b.mesh.colors.reserve(block.color.size());
    for (const auto& c : block.color) b.mesh.colors.push_back({c[0], c[1], c[2]});
    b.mesh.triangles.reserve(block.triangle.size());
    for (const auto& t : block.triangle) b.mesh.triangles.push_back({t[0], t[1], t[2]});
    if (std::string e = b.mesh.validate(); !e.empty()) {
      if (error) *error = what + ": " + e;
      return false;
    }
    update->blocks.push_back(std::move(b));
  }
  return true;
}

subvolume_list_t encodeSubvolumeList(const SubvolumeList& list, int64_t utime) {
  subvolume_list_t msg;
  msg.utime = utime;
  msg.map_epoch = list.map_epoch;
  msg.active_subvolume_id = list.active_submap;
  msg.block_size = list.block_size;
  for (const SubvolumeView& v : list.subvolumes) {
    msg.subvolume_ids.push_back(v.id);
    msg.poses.push_back(toPoseMsg(v.T_G_S));
    msg.anchor_keyframe_ids.push_back(v.anchor_keyframe);
    msg.num_blocks.push_back(static_cast<int32_t>(std::min<size_t>(v.num_blocks, INT32_MAX)));
    msg.bounds_min.push_back({v.min_S.x(), v.min_S.y(), v.min_S.z()});
    msg.bounds_max.push_back({v.max_S.x(), v.max_S.y(), v.max_S.z()});
  }
  msg.num_subvolumes = static_cast<int32_t>(msg.subvolume_ids.size());
  return msg;
}

bool decodeSubvolumeList(const subvolume_list_t& msg, SubvolumeList* list, std::string* error) {
  const int32_t n = msg.num_subvolumes;
  if (!countMatches(n, msg.subvolume_ids, "subvolume_ids", error) ||
      !countMatches(n, msg.poses, "poses", error) ||
      !countMatches(n, msg.anchor_keyframe_ids, "anchor_keyframe_ids", error) ||
      !countMatches(n, msg.num_blocks, "num_blocks", error) ||
      !countMatches(n, msg.bounds_min, "bounds_min", error) ||
      !countMatches(n, msg.bounds_max, "bounds_max", error)) {
    return false;
  }
  list->map_epoch = msg.map_epoch;
  list->active_submap = msg.active_subvolume_id;
  list->block_size = msg.block_size;
  list->subvolumes.clear();
  list->subvolumes.reserve(static_cast<size_t>(n));
  for (size_t i = 0; i < static_cast<size_t>(n); ++i) {
    SubvolumeView v;
    v.id = msg.subvolume_ids[i];
    std::string pose_error;
    const std::optional<Transformationd> T = fromPoseMsg(msg.poses[i], &pose_error);
    if (!T) {
      if (error) *error = "poses[" + std::to_string(i) + "]: " + pose_error;
      return false;
    }
    v.T_G_S = *T;
    v.active = v.id == msg.active_subvolume_id;
    v.anchor_keyframe = msg.anchor_keyframe_ids[i];
    v.num_blocks = msg.num_blocks[i] < 0 ? 0 : static_cast<size_t>(msg.num_blocks[i]);
    v.min_S = Eigen::Vector3f(msg.bounds_min[i][0], msg.bounds_min[i][1], msg.bounds_min[i][2]);
    v.max_S = Eigen::Vector3f(msg.bounds_max[i][0], msg.bounds_max[i][1], msg.bounds_max[i][2]);
    if (!v.min_S.allFinite() || !v.max_S.allFinite()) {
      if (error) *error = "bounds of subvolume " + std::to_string(v.id) + " are not finite";
      return false;
    }
    list->subvolumes.push_back(v);
  }
  return true;
}

}  // namespace cblox
