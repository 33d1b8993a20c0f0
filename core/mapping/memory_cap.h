#pragma once

// The cap on the map's memory (the `memory` part of config/mapper.yaml; README "Memory cap
// and overload"): which stage of the policy a depth frame is integrated under, decided from
// the map's accounted bytes (SubmapCollection::memoryBytes: blocks x bytes per block plus
// each layer's hash slots), and the two steps that enforce a stage on one frame: cutting far
// depth, and taking back the blocks a frame allocated at the cap.

#include <cstddef>
#include <cstdint>
#include <string>

#include <absl/container/flat_hash_set.h>

#include "core/geometry/image.h"
#include "core/geometry/pinhole_camera.h"
#include "core/geometry/se3.h"
#include "core/tsdf/tsdf_layer.h"

namespace cblox {

/// Settings of the memory cap. Plain value type.
struct MemoryCapConfig {
  /// The cap on the map's accounted bytes, MiB; 0 = no cap. 1024 MiB: on a NUC with 4 GiB
  /// it leaves room for the OS, the tracker (~0.1-0.2 GiB) and an export's projected copy
  /// of the map (up to the map's size again) without swapping or an OOM kill.
  size_t cap_mb = 1024;
  /// From this share of the cap on (0, 1], frames are integrated near-only: depth beyond
  /// near_distance_m is not integrated, so no block farther away is allocated.
  double near_only_fraction = 0.8;
  /// Near-only (and at the cap): depth beyond this many metres along the optical axis is
  /// cut (> 0).
  float near_distance_m = 2.0f;

  bool enabled() const { return cap_mb > 0; }
  size_t capBytes() const { return cap_mb * size_t{1024} * size_t{1024}; }
  /// Empty when valid, otherwise a message naming the offending field. Thread-safe.
  std::string validate() const;
};

/// The stage of the policy a frame is integrated under.
enum class MemoryCapState : uint8_t {
  kOff,       ///< no cap configured
  kBelow,     ///< below near_only_fraction of the cap: integrated as configured
  kNearOnly,  ///< depth beyond near_distance_m cut: near blocks only
  kFull,      ///< at or above the cap: near-only, and no new block (existing ones updated)
};
/// "off", "below", "near_only", "full". Thread-safe.
const char* memoryCapStateName(MemoryCapState state);

/// The stage for a map of `map_bytes`. Thread-safe (pure).
MemoryCapState memoryCapState(const MemoryCapConfig& config, size_t map_bytes);

/// Sets depth readings beyond `max_depth_m` to 0 (no measurement); returns how many.
/// Thread-safe (touches only `depth`).
size_t cutDepthBeyond(DepthImage* depth, float max_depth_m);

/// Sets to 0 the depth readings whose measured point, T_M_D * (back-projection through `K`),
/// lies in no allocated block of `layer`; returns how many. At the cap this spares the
/// integrator the work on blocks that would be refused anyway (blocks it still allocates
/// within truncation or along a ray are taken back by NewBlockRefusal). The caller must hold
/// the layer against writers. Thread-safe otherwise (touches only `depth`).
size_t cutDepthOutsideBlocks(DepthImage* depth, const PinholeIntrinsics& K,
                             const Transformation& T_M_D, const TsdfLayer& layer);

/// Refuses new blocks in one layer for one integration: remember() the layer's blocks before
/// it, removeNewBlocks() after it removes every block the integration allocated (and the
/// voxels it wrote there). The caller must hold the layer exclusively across both calls (the
/// integrator thread under Submap::lockForIntegration). Not thread-safe; reuse it per frame.
class NewBlockRefusal {
 public:
  void remember(const TsdfLayer& layer);
  /// Returns the number of blocks removed.
  size_t removeNewBlocks(TsdfLayer* layer);

 private:
  absl::flat_hash_set<uint64_t> before_;
};

}  // namespace cblox
