#include "core/mesh/block_mesher.h"

#include <array>
#include <cmath>

#include "core/mesh/marching_cubes.h"
#include "core/mesh/marching_cubes_tables.h"
#include "core/mesh/mesh_integrator.h"
#include "core/tsdf/block_index.h"

namespace cblox {

void BlockMesher::meshBlock(const TsdfLayer& layer, const Block& block, Mesh* mesh_out,
                            std::vector<MeshEdgeKey>* edge_keys) {
  // A block's cubes read local voxel indices 0 .. n per axis; normals read up to n + 1. So a
  // block's mesh depends only on its own voxels and those of its 7 upper neighbours (offsets
  // in {0, 1}^3), which is what makes re-meshing B and its 7 lower neighbours exact.
  const int n = layer.voxelsPerSide();
  const int p = n + 2;  // gathered side: local indices 0 .. n + 1
  const size_t gathered = static_cast<size_t>(p) * static_cast<size_t>(p) * static_cast<size_t>(p);
  distance_.assign(gathered, 0.0f);
  valid_.assign(gathered, 0);
  if (config_.use_color) color_.assign(gathered, Color{});
  const size_t edge_slots =
      static_cast<size_t>(n + 1) * static_cast<size_t>(n + 1) * static_cast<size_t>(n + 1) * 3;
  if (edge_vertex_.size() != edge_slots) edge_vertex_.assign(edge_slots, -1);

  const BlockIndex& bi = block.index();
  std::array<const Block*, 8> upper;  // index dx + 2 dy + 4 dz
  for (int o = 0; o < 8; ++o) {
    upper[static_cast<size_t>(o)] =
        o == 0 ? &block : layer.getBlock(bi + BlockIndex(o & 1, (o >> 1) & 1, (o >> 2) & 1));
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
        distance_[gi] = v.distance;
        valid_[gi] = 1;
        if (config_.use_color) color_[gi] = v.color;
      }
    }
  }

  const int stride[3] = {1, p, p * p};
  const float h = layer.voxelSize();
  const auto valid = [this](int idx) { return valid_[static_cast<size_t>(idx)] != 0; };
  const auto dist = [this](int idx) { return distance_[static_cast<size_t>(idx)]; };
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

  Mesh& mesh = *mesh_out;
  mesh.clear();
  if (edge_keys != nullptr) edge_keys->clear();
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
          complete = valid_[static_cast<size_t>(idx)] != 0;
          sdf[static_cast<size_t>(c)] = distance_[static_cast<size_t>(idx)];
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
          int& vertex = edge_vertex_[slot];
          if (vertex < 0) {
            const auto ilo = static_cast<size_t>(corner_idx[static_cast<size_t>(lo)]);
            const auto ihi = static_cast<size_t>(corner_idx[static_cast<size_t>(hi)]);
            const float d_lo = distance_[ilo];
            const float d_hi = distance_[ihi];
            const float t = zeroCrossingFraction(d_lo, d_hi);
            const GlobalVoxelIndex g_lo = block_origin + lo_local;
            GlobalVoxelIndex g_hi = g_lo;
            g_hi[axis] += 1;
            const Eigen::Vector3f p_lo = layer.globalVoxelCenter(g_lo);
            const Eigen::Vector3f p_hi = layer.globalVoxelCenter(g_hi);
            vertex = static_cast<int>(mesh.vertices.size());
            touched_.push_back(slot);
            mesh.vertices.push_back(p_lo + t * (p_hi - p_lo));
            if (config_.use_color) {
              mesh.colors.push_back(lerpColor(color_[ilo], color_[ihi], t));
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
            if (edge_keys != nullptr) edge_keys->push_back(MeshEdgeKey{g_lo.x(), g_lo.y(), g_lo.z(), axis});
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
  for (const size_t slot : touched_) edge_vertex_[slot] = -1;
  touched_.clear();
}

}  // namespace cblox
