#pragma once

#include <cstddef>
#include <string>

#include "core/geometry/se3.h"
#include "core/mesh/mesh.h"
#include "core/mesh/mesh_integrator.h"
#include "core/submap/submap.h"
#include "core/submap/submap_collection.h"
#include "core/tsdf/layer_config.h"
#include "core/tsdf/tsdf_layer.h"

namespace cblox {

/// Settings of subvolume fusion (fuseLayers, fuseSubmaps, projectCollection).
struct SubmapFusionConfig {
  /// Fused weights saturate here (as IntegratorConfig::max_weight, whose default it shares).
  /// Finite and >= min_weight.
  float max_weight = 10000.0f;
  /// Source voxels with a lower weight count as unobserved (a sample needing one is
  /// skipped). Finite and > 0, so never-observed voxels (weight 0) are never used.
  float min_weight = 1e-4f;
  /// At the rim of the observed region some of a sample's 8 corners are unobserved. The
  /// sample still counts when the observed corners carry at least this fraction of the
  /// trilinear weight (see fuseLayers); 1 = every needed corner must be observed (pure
  /// trilinear, loses a one-voxel rim of the source's observed region). In (0, 1].
  float min_sample_coverage = 0.5f;
  /// Fuse colours (weighted like the distance). Off: target colours are left as they are.
  bool use_color = true;
  /// Worker threads (the calling thread is one of them), in [1, 64]. The result does not
  /// depend on it: every target voxel is computed by exactly one thread.
  int num_threads = 2;

  /// Empty when valid, otherwise a message naming the offending field. Thread-safe.
  std::string validate() const;
};

/// What one fusion did. Counters are exact.
struct SubmapFusionStats {
  size_t source_blocks = 0;            ///< source blocks with a voxel of weight >= min_weight
  size_t target_blocks_visited = 0;    ///< target blocks whose voxels were sampled
  size_t target_blocks_allocated = 0;  ///< target blocks newly allocated and kept
  size_t voxels_fused = 0;             ///< target voxels updated
  size_t voxels_sampled = 0;           ///< target voxels sampled (the others were skipped)
  double seconds = 0.0;                ///< wall time

  SubmapFusionStats& operator+=(const SubmapFusionStats& o) {
    source_blocks += o.source_blocks;
    target_blocks_visited += o.target_blocks_visited;
    target_blocks_allocated += o.target_blocks_allocated;
    voxels_fused += o.voxels_fused;
    voxels_sampled += o.voxels_sampled;
    seconds += o.seconds;
    return *this;
  }
};

/// Fuses the TSDF `source` (frame S) into `target` (frame T), T_T_S mapping S into T.
/// The layers may have different voxel and block sizes.
///
/// Exact behaviour:
/// - Region: for every source block holding a voxel with weight >= min_weight, the cube
///   spanned from the centre of voxel (first - 1,1,1) to the first voxel centre of its
///   +1,+1,+1 neighbour (every cell with a corner in the block) is mapped into T; every
///   target block overlapping the axis-aligned bounding box of that cube is allocated if
///   missing and each of its voxels is sampled once, except where a cube of 4^3 target
///   voxels can read no observed source block (the bounding box of its samples, widened well
///   beyond float rounding, meets none): those samples would all fail and are skipped, so the
///   result is the same (voxels_sampled counts the rest). Around a sparse source (isolated
///   blocks under a rotation) most visited voxels are skipped this way.
/// - Sample: the target voxel centre p_T goes to p_S = T_T_S^-1 * p_T; with q = p_S / s - 1/2
///   (s: source voxel size; voxel i has its centre at q = i), base = floor(q), f = q - base,
///   the 8 corners base + o, o in {0,1}^3, have trilinear coefficients
///   c_o = prod_axes (o ? f : 1 - f). A corner with c_o == 0 is neither needed nor read
///   (so a voxel-aligned point reads one voxel); every other corner is observed when it
///   exists with weight >= min_weight. If all needed corners are observed the sample is
///   d_S = sum c_o d_o, w_S = sum c_o w_o, colour_S = sum c_o colour_o (unrounded).
///   Otherwise, with the coverage C = sum of c_o over the observed corners: if
///   C >= min_sample_coverage the sample is d_S = sum_obs c_o d_o / C,
///   colour_S = sum_obs c_o colour_o / C and w_S = sum_obs c_o w_o (the weight is not
///   renormalised, so rim samples count less); else the sample fails and the target voxel
///   is untouched.
///   q = A * g + c (g: target global voxel index, A = R_S_T * t / s, t: target voxel size),
///   evaluated in double at each target block's first voxel and stepped in float from there,
///   so an identity transform (or a translation by whole voxels) between equal grids maps
///   voxel centres onto voxel centres exactly.
/// - Merge into the target voxel (d_T, w_T, colour_T): if w_T == 0 it becomes
///   (d_S, min(w_S, max_weight), round(colour_S)); otherwise w = w_T + w_S,
///   d = (d_T w_T + d_S w_S) / w, colour = round((colour_T w_T + colour_S w_S) / w) per
///   channel, weight = min(w, max_weight). Colours are written only when use_color. Updated
///   target blocks get Block::setUpdated(true) (for the incremental mesher).
/// - Target blocks newly allocated here that received no sample with every needed corner
///   observed (none, or rim samples only) are removed again, their voxels uncounted: rim
///   samples extend an existing block but never allocate one, so repeated fusions do not
///   grow the map by a one-voxel rim each (measured: two halves of an orbit fused 1179
///   blocks instead of 1124 this way, the whole integration 1067).
/// Throws std::invalid_argument for an invalid config, a non-finite T_T_S, a null target
/// or source == target. Thread safety: nothing else may touch `target` during the call;
/// `source` is only read (concurrent readers are fine). Uses config.num_threads threads.
SubmapFusionStats fuseLayers(const TsdfLayer& source, const Transformationd& T_T_S,
                             const SubmapFusionConfig& config, TsdfLayer* target);

/// Fuses submap `source` into submap `target` (both finished) with
/// T_T_S = T_G_T^-1 * T_G_S (poses read once at the start): fuseLayers, then the source's
/// keyframe ids are added to the target's and the target's statistics refreshed. The
/// source is unchanged; the caller removes it from its collection. Throws
/// std::invalid_argument when either submap is still active, target is null, they are the
/// same submap, or fuseLayers throws. Thread safety: call on the fusion worker, which owns
/// finished submaps (see SubmapCollection); pose updates may run concurrently.
SubmapFusionStats fuseSubmaps(const Submap& source, Submap* target,
                              const SubmapFusionConfig& config);

/// The whole collection as one TSDF layer in the global frame G (for display and export):
/// starting from an empty layer with `layer_config`, every submap is fused in (fuseLayers
/// with T_G_M) in creation order, using one poseSnapshot() so all poses come from the same
/// instant. An empty collection gives an empty layer. With include_active, the active
/// submap is fused while holding its layer lock (Submap::lockLayer: integration waits for
/// that long); without, only finished submaps are used and integration is never blocked.
/// Throws std::invalid_argument for an invalid config. Thread safety: call on the fusion
/// worker (it reads finished layers without locks). `stats` (optional) receives the sum.
TsdfLayer projectCollection(const SubmapCollection& collection, const LayerConfig& layer_config,
                            const SubmapFusionConfig& config, bool include_active = true,
                            SubmapFusionStats* stats = nullptr);

/// Mesh of projectCollection() in G: MeshIntegrator over every block, extractMesh(true)
/// (connected). Same thread-safety and exceptions as projectCollection, plus MeshConfig's.
Mesh meshCollection(const SubmapCollection& collection, const LayerConfig& layer_config,
                    const SubmapFusionConfig& config, const MeshConfig& mesh_config,
                    bool include_active = true);

}  // namespace cblox
