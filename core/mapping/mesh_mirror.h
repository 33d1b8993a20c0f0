#pragma once

// The receiving end of the mapper's mesh stream (mesh_streamer.h): the block meshes and
// subvolume poses a receiver holds after applying what it got, and whether that is the whole
// map. cblox-viewer keeps one; so can any program that wants the map's surface live.

#include <cstddef>
#include <cstdint>
#include <map>
#include <string>

#include "core/mapping/mesh_update.h"
#include "core/mesh/mesh.h"

namespace cblox {

/// Block meshes by subvolume (in its frame S), and the newest subvolume list.
/// Not thread-safe (one thread applies and reads).
class MeshMirror {
 public:
  struct Result {
    bool applied = false;  ///< false: refused (`error` says why), nothing changed
    /// Messages were lost before this one (its sequence does not follow the last one's, or
    /// the first one seen does not begin a refresh): what is held may be incomplete until a
    /// refresh (ask the mapper: command mesh_refresh).
    bool gap = false;
    std::string error;
  };
  using Blocks = std::map<uint64_t, QuantizedBlockMesh>;  ///< by packGridIndex(block index)

  /// Applies one message: a new map epoch or refresh_start drops every block first; removed
  /// subvolumes are dropped; each block's mesh replaces what was held (an empty one removes
  /// it). Refused whole, nothing changed, when block_size is not finite and > 0 or a block
  /// breaks QuantizedBlockMesh::validate() or has a block index outside the packable range.
  Result apply(const MeshUpdate& update);
  /// The newest subvolume list (poses, bounds; what meshInG places blocks with).
  void applySubvolumes(const SubvolumeList& list);

  /// True when everything since the last refresh start arrived in order and the last message
  /// said nothing is pending: the blocks are the map as meshed at that message.
  bool complete() const { return synced_ && pending_ == 0; }
  /// True when everything since the last refresh start arrived in order (blocks may still
  /// be pending): false before the first refresh start and after a gap, when a receiver
  /// asks for a refresh.
  bool synced() const { return synced_; }
  int64_t mapEpoch() const { return epoch_; }
  int64_t lastSequence() const { return last_sequence_; }
  float blockSize() const { return block_size_; }
  const std::map<SubmapId, Blocks>& blocks() const { return blocks_; }
  const SubvolumeList& subvolumes() const { return subvolumes_; }
  size_t numBlocks() const;

  /// Every held block's mesh in G: through the pose of its subvolume in the newest list of
  /// the same map epoch (blocks of subvolumes it does not name are left out).
  Mesh meshInG() const;

 private:
  std::map<SubmapId, Blocks> blocks_;
  SubvolumeList subvolumes_;
  int64_t epoch_ = 0;
  int64_t last_sequence_ = 0;
  size_t pending_ = 0;
  float block_size_ = 0.0f;
  bool synced_ = false;
  bool seen_any_ = false;
};

}  // namespace cblox
