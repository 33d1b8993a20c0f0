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


MeshIntegrator::MeshIntegrator(const TsdfLayer& layer, MeshConfig config)
    : layer_(layer), config_(config) {
  const std::string error = config_.validate();
  if (!error.empty()) throw std::invalid_argument("MeshConfig: " + error);
}

void MeshIntegrator::clear() {
  meshes_.clear();
  edge_keys_.clear();
}

size_t MeshIntegrator::update(bool only_updated_blocks, bool clear_updated_flags) {
  absl::flat_hash_set<uint64_t> dirty;
  std::vector<Block*> consumed;  // blocks whose updated flag this call consumes
  const auto add_with_lower_neighbours = [&](const BlockIndex& index, bool include_self) {
    if (include_self && layer_.getBlock(index) != nullptr) dirty.insert(packGridIndex(index));
    for (const auto& o : kMeshLowerNeighbours) {
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
  std::vector<Mesh> results(keys.size());
  std::vector<std::vector<EdgeKey>> result_edges(keys.size());

  std::atomic<size_t> next{0};
  const auto worker = [&]() {
    BlockMesher mesher(config_);
    for (size_t i = next.fetch_add(1); i < keys.size(); i = next.fetch_add(1)) {
      mesher.meshBlock(layer_, *layer_.getBlock(unpackGridIndex(keys[i])), &results[i],
                       &result_edges[i]);
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
    meshes_[keys[i]] = std::move(results[i]);
    edge_keys_[keys[i]] = std::move(result_edges[i]);
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
