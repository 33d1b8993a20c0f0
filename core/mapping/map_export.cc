#include "core/mapping/map_export.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <optional>
#include <system_error>

#include "core/common/text_format.h"
#include "core/io/ply_io.h"
#include "core/mapping/output_path.h"

namespace cblox {
namespace {

using Clock = std::chrono::steady_clock;

// Copies every block of `source` into the empty `target` (same geometry). The caller holds
// whatever lock `source` needs.
void copyLayer(const TsdfLayer& source, TsdfLayer* target) {
  for (const auto& [key, block] : source.blocks()) {
    Block* copy = target->allocateBlock(block->index());
    std::copy_n(block->voxels(), block->numVoxels(), copy->voxels());
  }
}

// The layer of `submap` for reading on the worker: a finished layer is the worker's own and
// is read in place; an active one is copied under its layer lock (held for the copy only).
const TsdfLayer& readableLayer(const Submap& submap, std::optional<TsdfLayer>* copy) {
  if (submap.isFinished()) return submap.layer();
  copy->emplace(submap.layerConfig());
  const std::unique_lock<std::mutex> lock = submap.lockLayer();
  copyLayer(submap.layer(), &**copy);
  return **copy;
}

}  // namespace

MapperReply exportGlobalMesh(const SubmapCollection& collection, const MapExportConfig& config,
                             const std::filesystem::path& output_dir, const std::string& path_arg) {
  MapperReply reply;
  std::string error;
  const auto path = writableOutputPath(output_dir, path_arg, &error);
  if (!path) {
    reply.message = error;
    return reply;
  }
  const Clock::time_point start = Clock::now();
  TsdfLayer global(config.layer);
  size_t submaps = 0;
  for (const SubmapPose& pose : collection.poseSnapshot()) {
    const std::shared_ptr<Submap> submap = collection.getSubmap(pose.id);
    if (!submap) continue;  // removed since the snapshot
    std::optional<TsdfLayer> copy;
    const TsdfLayer& layer = readableLayer(*submap, &copy);
    fuseLayers(layer, pose.T_G_M, config.fusion, &global);
    ++submaps;
  }
  MeshIntegrator mesher(global, config.mesh);
  mesher.update(/*only_updated_blocks=*/false);
  const Mesh mesh = mesher.extractMesh(/*connected=*/true);
  if (mesh.numVertices() == 0) {
    reply.message = "the map is empty (" + std::to_string(submaps) +
                    " subvolumes, no surface yet): nothing written";
    return reply;
  }
  std::error_code ec;
  std::filesystem::create_directories(path->parent_path(), ec);
  if (!writePly(path->string(), mesh, PlyFormat::kBinaryLittleEndian, &error)) {
    reply.message = error;
    return reply;
  }
  const double seconds = secondsSince(start);
  reply.ok = true;
  reply.message = "wrote " + path->string() + ": " + std::to_string(mesh.numVertices()) +
                  " vertices, " + std::to_string(mesh.numTriangles()) + " triangles from " +
                  std::to_string(submaps) + " subvolumes in " + fixed(seconds, 3) + " s";
  reply.values = {{"path", path->string()},
                  {"vertices", std::to_string(mesh.numVertices())},
                  {"triangles", std::to_string(mesh.numTriangles())},
                  {"subvolumes", std::to_string(submaps)},
                  {"seconds", fixed(seconds, 3)}};
  return reply;
}

MapperReply exportSubvolumeMeshes(const SubmapCollection& collection,
                                  const MapExportConfig& config,
                                  const std::filesystem::path& output_dir, const std::string& dir_arg) {
  MapperReply reply;
  std::string error;
  const auto dir = writableOutputPath(output_dir, dir_arg, &error);
  if (!dir) {
    reply.message = error;
    return reply;
  }
  std::error_code ec;
  std::filesystem::create_directories(*dir, ec);
  if (ec || !std::filesystem::is_directory(*dir)) {
    reply.message = "cannot create directory " + dir->string() + ": " + ec.message();
    return reply;
  }
  const Clock::time_point start = Clock::now();
  size_t files = 0, vertices = 0, triangles = 0;
  for (const SubmapPose& pose : collection.poseSnapshot()) {
    const std::shared_ptr<Submap> submap = collection.getSubmap(pose.id);
    if (!submap) continue;
    std::optional<TsdfLayer> copy;
    const TsdfLayer& layer = readableLayer(*submap, &copy);
    MeshIntegrator mesher(layer, config.mesh);
    mesher.update(/*only_updated_blocks=*/false);
    Mesh mesh = transformMesh(pose.T_G_M.cast<float>(), mesher.extractMesh(/*connected=*/true));
    if (mesh.numVertices() == 0) continue;
    mesh.colors.assign(mesh.numVertices(), submapColor(pose.id));
    char name[64];
    std::snprintf(name, sizeof(name), "submap_%04lld.ply", static_cast<long long>(pose.id));
    if (!writePly((*dir / name).string(), mesh, PlyFormat::kBinaryLittleEndian, &error)) {
      reply.message = error;
      return reply;
    }
    ++files;
    vertices += mesh.numVertices();
    triangles += mesh.numTriangles();
  }
  const double seconds = secondsSince(start);
  reply.ok = true;
  reply.message = "wrote " + std::to_string(files) + " subvolume meshes to " + dir->string() +
                  " (" + std::to_string(vertices) + " vertices) in " + fixed(seconds, 3) + " s";
  reply.values = {{"path", dir->string()},
                  {"count", std::to_string(files)},
                  {"vertices", std::to_string(vertices)},
                  {"triangles", std::to_string(triangles)},
                  {"seconds", fixed(seconds, 3)}};
  return reply;
}

Color submapColor(SubmapId id) {
  // Golden-ratio steps around the hue circle: neighbouring ids get far-apart hues.
  const double hue = std::fmod(0.13 + 0.618033988749895 * static_cast<double>(id), 1.0) * 6.0;
  const double value = 0.95, saturation = 0.85;
  const int sector = static_cast<int>(hue) % 6;
  const double f = hue - std::floor(hue);
  const double p = value * (1.0 - saturation), q = value * (1.0 - saturation * f),
               t = value * (1.0 - saturation * (1.0 - f));
  double r = 0, g = 0, b = 0;
  switch (sector) {
    case 0:
      r = value, g = t, b = p;
      break;
    case 1:
      r = q, g = value, b = p;
      break;
    case 2:
      r = p, g = value, b = t;
      break;
    case 3:
      r = p, g = q, b = value;
      break;
    case 4:
      r = t, g = p, b = value;
      break;
    default:
      r = value, g = p, b = q;
      break;
  }
  auto channel = [](double c) { return static_cast<uint8_t>(std::lround(c * 255.0)); };
  return Color{channel(r), channel(g), channel(b)};
}

}  // namespace cblox
