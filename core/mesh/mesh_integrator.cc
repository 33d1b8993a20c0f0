#include "core/mesh/mesh_integrator.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <exception>
#include <sstream>
#include <stdexcept>
#include <thread>

#include <absl/container/flat_hash_set.h>

#include "core/mesh/marching_cubes.h"
#include "core/mesh/marching_cubes_tables.h"
#include "core/tsdf/block_index.h"

namespace cblox {

std::string MeshConfig::validate() const {
  std::ostringstream msg;
  if (!std::isfinite(min_weight) || min_weight <= 0.0f) {
    msg << "min_weight must be finite and > 0, got " << min_weight;
  } else if (num_threads < 1) {
    msg << "num_threads must be >= 1, got " << num_threads;
  }
  return msg.str();
}

namespace {

// The 7 lower neighbours of a block (offsets in {-1, 0}^3 minus the origin): exactly the
// blocks whose cubes can have a corner in the block.
constexpr std::array<std::array<int, 3>, 7> kLowerNeighbours = {
    {{-1, 0, 0}, {0, -1, 0}, {0, 0, -1}, {-1, -1, 0}, {-1, 0, -1}, {0, -1, -1}, {-1, -1, -1}}};

}  // namespace

// Per-thread work buffers, reused across blocks.
struct MeshIntegrator::Scratch {
  // Voxels of the block and a two-voxel apron on its high sides (from the +x, +y, +z
  // neighbours), i.e. local indices 0 .. n+1 per axis, x fastest.
  std::vector<float> distance;
  std::vector<uint8_t> valid;  // weight >= min_weight (0 for missing blocks)
  std::vector<Color> color;
  // Vertex index per (cube-corner local index 0..n, axis), -1 when none yet.
  std::vector<int> edge_vertex;
  std::vector<size_t> touched;
};

MeshIntegrator::MeshIntegrator(const TsdfLayer& layer, MeshConfig config)
    : layer_(layer), config_(config) {
  const std::string error = config_.validate();
  if (!error.empty()) throw std::invalid_argument("MeshConfig: " + error);
}

void MeshIntegrator::clear() {
  meshes_.clear();
  edge_keys_.clear();
}

void MeshIntegrator::meshBlock(const Block& block, Scratch* s, BlockResult* result) const {
  // A block's cubes read local voxel indices 0 .. n per axis; normals read up to n + 1. So a
  // block's mesh depends only on its own voxels and those of its 7 upper neighbours (offsets
  // in {0, 1}^3), which is what makes re-meshing B and its 7 lower neighbours exact.
  const int n = layer_.voxelsPerSide();
  const int p = n + 2;  // gathered side: local indices 0 .. n + 1
  const size_t gathered = static_cast<size_t>(p) * static_cast<size_t>(p) * static_cast<size_t>(p);
  s->distance.assign(gathered, 0.0f);
  s->valid.assign(gathered, 0);
  if (config_.use_color) s->color.assign(gathered, Color{});
  const size_t edge_slots =
      static_cast<size_t>(n + 1) * static_cast<size_t>(n + 1) * static_cast<size_t>(n + 1) * 3;
  if (s->edge_vertex.size() != edge_slots) s->edge_vertex.assign(edge_slots, -1);

  const BlockIndex& bi = block.index();
  std::array<const Block*, 8> upper;  // index dx + 2 dy + 4 dz
  for (int o = 0; o < 8; ++o) {
    upper[static_cast<size_t>(o)] =
        o == 0 ? &block : layer_.getBlock(bi + BlockIndex(o & 1, (o >> 1) & 1, (o >> 2) & 1));
  }
  size_t gi = 0;
  for (int z = 0; z < p; ++z) {
    const int oz = z >= n ? 1 : 0;
    for (int y = 0; y < p; ++y) {
      const int oy = y >= n ? 1 : 0;
      for (int x = 0; x < p; ++x, ++gi) {
        const int ox = x >= n ? 1 : 0;
        const Block* b = upper[static_cast<size_t>(ox + 2 * oy + 4 * oz)];
        if (b == nullptr) continue;
        const TsdfVoxel& v = b->voxel(GridIndex(x - ox * n, y - oy * n, z - oz * n));
        if (v.weight < config_.min_weight) continue;
        s->distance[gi] = v.distance;
        s->valid[gi] = 1;
        if (config_.use_color) s->color[gi] = v.color;
      }
    }
  }

  const int stride[3] = {1, p, p * p};
  const float h = layer_.voxelSize();
  const auto valid = [s](int idx) { return s->valid[static_cast<size_t>(idx)] != 0; };
  const auto dist = [s](int idx) { return s->distance[static_cast<size_t>(idx)]; };
  // TSDF gradient at gathered voxel `idx` with local coordinates `local`: central
  // differences; where the stencil leaves the gathered region (a block's lower faces) or
  // meets an unobserved voxel, the second-order one-sided difference, then first-order;
  // 0 along an axis with no observed neighbour.
  const auto gradient = [&](int idx, const GridIndex& local) {
    Eigen::Vector3f g;
    const float d0 = dist(idx);
    for (int a = 0; a < 3; ++a) {
      const int st = stride[a];
      const int i = local[a];
      const bool has_m1 = i >= 1 && valid(idx - st);
      const bool has_m2 = i >= 2 && has_m1 && valid(idx - 2 * st);
      const bool has_p1 = i + 1 < p && valid(idx + st);
      const bool has_p2 = i + 2 < p && has_p1 && valid(idx + 2 * st);
      if (has_m1 && has_p1) {
        g[a] = (dist(idx + st) - dist(idx - st)) / (2.0f * h);
      } else if (has_p2) {
        g[a] = (-3.0f * d0 + 4.0f * dist(idx + st) - dist(idx + 2 * st)) / (2.0f * h);
      } else if (has_m2) {
        g[a] = (3.0f * d0 - 4.0f * dist(idx - st) + dist(idx - 2 * st)) / (2.0f * h);
      } else if (has_p1) {
        g[a] = (dist(idx + st) - d0) / h;
      } else if (has_m1) {
        g[a] = (d0 - dist(idx - st)) / h;
      } else {
        g[a] = 0.0f;
      }
    }
    return g;
  };
  const auto gathered_index = [p](const GridIndex& l) { return l.x() + p * (l.y() + p * l.z()); };

  Mesh& mesh = result->mesh;
  mesh.clear();
  result->edge_keys.clear();
  const GlobalVoxelIndex block_origin = bi * n;
  std::array<int, 8> corner_idx;
  std::array<float, 8> sdf;
  std::array<int, 12> vertex_of_edge;
  std::array<std::array<int, 3>, 5> tris;

  for (int z = 0; z < n; ++z) {
    for (int y = 0; y < n; ++y) {
      for (int x = 0; x < n; ++x) {
        bool complete = true;
        for (int c = 0; c < 8 && complete; ++c) {
          const int idx =
              gathered_index(GridIndex(x + mc::kCornerOffsets[c][0], y + mc::kCornerOffsets[c][1],
                                       z + mc::kCornerOffsets[c][2]));
          corner_idx[static_cast<size_t>(c)] = idx;
          complete = s->valid[static_cast<size_t>(idx)] != 0;
          sdf[static_cast<size_t>(c)] = s->distance[static_cast<size_t>(idx)];
        }
        if (!complete) continue;
        const int config = cubeConfiguration(sdf);
        const int edges = mc::kEdgeTable[config];
        if (edges == 0) continue;

        for (int e = 0; e < 12; ++e) {
          if ((edges & (1 << e)) == 0) continue;
          const int lo = mc::kEdgeLowerCorner[e];
          const int hi = mc::kEdgeUpperCorner[e];
          const int axis = mc::kEdgeAxis[e];
          const GridIndex lo_local(x + mc::kCornerOffsets[lo][0], y + mc::kCornerOffsets[lo][1],
                                   z + mc::kCornerOffsets[lo][2]);
          const auto slot = static_cast<size_t>(
              ((lo_local.z() * (n + 1) + lo_local.y()) * (n + 1) + lo_local.x()) * 3 + axis);
          int& vertex = s->edge_vertex[slot];
          if (vertex < 0) {
            const auto ilo = static_cast<size_t>(corner_idx[static_cast<size_t>(lo)]);
            const auto ihi = static_cast<size_t>(corner_idx[static_cast<size_t>(hi)]);
            const float d_lo = s->distance[ilo];
            const float d_hi = s->distance[ihi];
            const float t = zeroCrossingFraction(d_lo, d_hi);
            const GlobalVoxelIndex g_lo = block_origin + lo_local;
            GlobalVoxelIndex g_hi = g_lo;
            g_hi[axis] += 1;
            const Eigen::Vector3f p_lo = layer_.globalVoxelCenter(g_lo);
            const Eigen::Vector3f p_hi = layer_.globalVoxelCenter(g_hi);
            vertex = static_cast<int>(mesh.vertices.size());
            s->touched.push_back(slot);
            mesh.vertices.push_back(p_lo + t * (p_hi - p_lo));
            if (config_.use_color) {
              mesh.colors.push_back(lerpColor(s->color[ilo], s->color[ihi], t));
            }
            if (config_.compute_normals) {
              GridIndex hi_local = lo_local;
              hi_local[axis] += 1;
              const Eigen::Vector3f n_lo = gradient(static_cast<int>(ilo), lo_local);
              const Eigen::Vector3f n_hi = gradient(static_cast<int>(ihi), hi_local);
              Eigen::Vector3f normal = n_lo + t * (n_hi - n_lo);
              const float norm = normal.norm();
              if (norm > 1e-12f && std::isfinite(norm)) {
                normal /= norm;
              } else {
                // Degenerate gradient: the edge direction towards the positive side.
                normal = Eigen::Vector3f::Zero();
                normal[axis] = d_hi > d_lo ? 1.0f : -1.0f;
              }
              mesh.normals.push_back(normal);
            }
            result->edge_keys.push_back(EdgeKey{g_lo.x(), g_lo.y(), g_lo.z(), axis});
          }
          vertex_of_edge[static_cast<size_t>(e)] = vertex;
        }
        const int num_tris = cubeTriangles(config, &tris);
        for (int i = 0; i < num_tris; ++i) {
          const auto& t = tris[static_cast<size_t>(i)];
          mesh.triangles.emplace_back(vertex_of_edge[static_cast<size_t>(t[0])],
                                      vertex_of_edge[static_cast<size_t>(t[1])],
                                      vertex_of_edge[static_cast<size_t>(t[2])]);
        }
      }
    }
  }
  for (const size_t slot : s->touched) s->edge_vertex[slot] = -1;
  s->touched.clear();
}

size_t MeshIntegrator::update(bool only_updated_blocks, bool clear_updated_flags) {
  absl::flat_hash_set<uint64_t> dirty;
  std::vector<Block*> consumed;  // blocks whose updated flag this call consumes
  const auto add_with_lower_neighbours = [&](const BlockIndex& index, bool include_self) {
    if (include_self && layer_.getBlock(index) != nullptr) dirty.insert(packGridIndex(index));
    for (const auto& o : kLowerNeighbours) {
      const BlockIndex neighbour = index + BlockIndex(o[0], o[1], o[2]);
      if (layer_.getBlock(neighbour) != nullptr) dirty.insert(packGridIndex(neighbour));
    }
  };

  // Blocks that left the layer: drop their meshes, re-mesh the blocks whose cubes used them.
  std::vector<uint64_t> removed;
  for (const auto& [key, mesh] : meshes_) {
    if (layer_.getBlock(unpackGridIndex(key)) == nullptr) removed.push_back(key);
  }
  for (const uint64_t key : removed) {
    meshes_.erase(key);
    edge_keys_.erase(key);
    add_with_lower_neighbours(unpackGridIndex(key), /*include_self=*/false);
  }

  // Block::updated is the only thing the mesher writes; TsdfLayer hands out non-const Block
  // pointers through its (const) block map, which is what makes clearing the flag possible.
  for (const auto& [key, block_ptr] : layer_.blocks()) {
    Block* block = block_ptr.get();
    if (!block->updated()) {
      if (!only_updated_blocks) dirty.insert(key);
      continue;
    }
    consumed.push_back(block);
    dirty.insert(key);
    add_with_lower_neighbours(block->index(), /*include_self=*/false);
  }

  std::vector<uint64_t> keys(dirty.begin(), dirty.end());
  std::sort(keys.begin(), keys.end());
  std::vector<BlockResult> results(keys.size());

  std::atomic<size_t> next{0};
  const auto worker = [&]() {
    Scratch scratch;
    for (size_t i = next.fetch_add(1); i < keys.size(); i = next.fetch_add(1)) {
      meshBlock(*layer_.getBlock(unpackGridIndex(keys[i])), &scratch, &results[i]);
    }
  };
  const size_t num_threads =
      std::min(static_cast<size_t>(config_.num_threads), std::max<size_t>(keys.size(), 1));
  std::vector<std::exception_ptr> errors(num_threads);
  {
    std::vector<std::thread> threads;
    threads.reserve(num_threads - 1);
    const auto guarded = [&](size_t t) {
      try {
        worker();
      } catch (...) {
        errors[t] = std::current_exception();
        next.store(keys.size());  // stop the others early
      }
    };
    for (size_t t = 1; t < num_threads; ++t) threads.emplace_back(guarded, t);
    guarded(0);
    for (std::thread& th : threads) th.join();
  }
  for (const std::exception_ptr& e : errors) {
    if (e) std::rethrow_exception(e);
  }

  for (size_t i = 0; i < keys.size(); ++i) {
    meshes_[keys[i]] = std::move(results[i].mesh);
    edge_keys_[keys[i]] = std::move(results[i].edge_keys);
  }
  if (clear_updated_flags) {
    for (Block* block : consumed) block->setUpdated(false);
  }
  return keys.size();
}

Mesh MeshIntegrator::extractMesh(bool connected) const {
  std::vector<uint64_t> keys;
  keys.reserve(meshes_.size());
  for (const auto& [key, mesh] : meshes_) keys.push_back(key);
  std::sort(keys.begin(), keys.end());

  Mesh out;
  if (!connected) {
    for (const uint64_t key : keys) out.append(meshes_.at(key));
    return out;
  }

  out.colors.clear();
  absl::flat_hash_map<EdgeKey, int> vertex_of_edge;
  bool first = true;
  std::vector<int> remap;
  for (const uint64_t key : keys) {
    const Mesh& mesh = meshes_.at(key);
    if (mesh.empty()) continue;
    const std::vector<EdgeKey>& edge_keys = edge_keys_.at(key);
    const bool colors = mesh.hasColors() && (first || out.hasColors());
    const bool normals = mesh.hasNormals() && (first || out.hasNormals());
    if (!colors) out.colors.clear();
    if (!normals) out.normals.clear();
    first = false;
    remap.resize(mesh.numVertices());
    for (size_t v = 0; v < mesh.numVertices(); ++v) {
      const auto [it, inserted] =
          vertex_of_edge.try_emplace(edge_keys[v], static_cast<int>(out.vertices.size()));
      if (inserted) {
        out.vertices.push_back(mesh.vertices[v]);
        if (colors) out.colors.push_back(mesh.colors[v]);
        if (normals) out.normals.push_back(mesh.normals[v]);
      }
      remap[v] = it->second;
    }
    for (const Eigen::Vector3i& t : mesh.triangles) {
      out.triangles.emplace_back(remap[static_cast<size_t>(t[0])], remap[static_cast<size_t>(t[1])],
                                 remap[static_cast<size_t>(t[2])]);
    }
  }
  return out;
}

}  // namespace cblox
