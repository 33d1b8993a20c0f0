#pragma once

#include <cstddef>
#include <string>

namespace cblox {

/// Settings of the mapper's incremental mesh stream (MapperConfig::mesh_stream,
/// mesh_streamer.h; the `mesh_stream` part of config/mapper.yaml). Plain value type.
struct MeshStreamConfig {
  /// Publish the changed mesh blocks and the subvolume list every period (when the process
  /// gives the mapper a place to publish them: cblox-mapper does, on CBLOX_MESH_UPDATE and
  /// CBLOX_SUBVOLUMES).
  bool enabled = true;
  /// Seconds between two updates; finite, in [0.05, 60].
  double period_s = 1.0;
  /// Mesh bytes one period may send (positions, colours, triangles); blocks beyond it wait
  /// for the next period (mesh_update_t.blocks_pending). At least max_message_bytes.
  size_t max_bytes_per_period = size_t{4} << 20;
  /// One message carries at most this many mesh bytes (a larger period is split into several
  /// messages); a single block larger than it goes alone. In [4 KiB, 4 MiB): UDP multicast
  /// receivers need the whole message in their socket buffer.
  size_t max_message_bytes = size_t{256} << 10;
  /// A full refresh (every block with a surface sent again, receivers drop what they hold
  /// first) every this many seconds, spread over periods by max_bytes_per_period; 0 = only
  /// when a receiver asks (command mesh_refresh). Finite, 0 or >= period_s.
  double refresh_period_s = 0.0;
  /// Vertex colours in the stream (3 bytes per vertex).
  bool use_color = true;

  /// Empty when valid, otherwise a message naming the offending field. Thread-safe.
  std::string validate() const;
};

}  // namespace cblox
