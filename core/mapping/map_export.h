#pragma once

// Mesh exports of the subvolume map (the worker's commands export_mesh and
// export_submap_meshes): the whole map fused into one volume, or one mesh per subvolume.

#include <filesystem>
#include <string>

#include "core/geometry/color.h"
#include "core/mapping/mapper_command.h"
#include "core/mesh/mesh_integrator.h"
#include "core/submap/submap_collection.h"
#include "core/submap/submap_fusion.h"
#include "core/tsdf/layer_config.h"

namespace cblox {

/// What the exports need of the mapper's settings. Plain value type.
struct MapExportConfig {
  LayerConfig layer;          ///< of the global volume (the subvolumes')
  SubmapFusionConfig fusion;  ///< subvolumes into the global volume
  MeshConfig mesh;
};

/// Fuses every subvolume into one volume and writes its mesh (binary PLY) to `path`,
/// resolved inside `output_dir` (resolveOutputPath; confined there on disk too). Reads
/// finished layers in place and copies an active one under its layer lock (held for the copy
/// only), so call it only where finished layers may be read: the mapper's worker thread
/// (SubmapCollection's rule). The reply says what was written (values path, vertices,
/// triangles, subvolumes, seconds) or why nothing was (reply.ok false). Never throws for a
/// bad path or an empty map.
MapperReply exportGlobalMesh(const SubmapCollection& collection, const MapExportConfig& config,
                             const std::filesystem::path& output_dir, const std::string& path);

/// One mesh per subvolume, in the global frame and coloured by submapColor(), as
/// `<dir>/submap_NNNN.ply`; `dir` as `path` above (created). Same thread rule and reply
/// (values path, count, vertices, triangles, seconds).
MapperReply exportSubvolumeMeshes(const SubmapCollection& collection,
                                  const MapExportConfig& config,
                                  const std::filesystem::path& output_dir, const std::string& dir);

/// A distinct colour per submap id (golden-ratio hue steps, full saturation, bright), for
/// per-submap meshes. Thread-safe (pure).
Color submapColor(SubmapId id);

}  // namespace cblox
