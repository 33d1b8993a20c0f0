// Google Benchmark: the layer's block map (absl::flat_hash_map keyed by the packed block
// index) against std::unordered_map, on the access pattern of ray casting with voxel
// carving: every block of a 6 x 4 x 3 m room is allocated (free space and walls), and the
// queries are the blocks crossed by rays from random points in the room to its walls.
//
//   build/test/bench/cblox-bench-block-hash-map --benchmark_repetitions=3

#include <benchmark/benchmark.h>

#include <random>
#include <unordered_map>
#include <vector>

#include <absl/container/flat_hash_map.h>

#include "core/integrator/grid_ray_traversal.h"
#include "core/tsdf/block_index.h"

namespace cblox {
namespace {

constexpr float kBlockSize = 0.16f;  // 8 voxels of 2 cm

struct Workload {
  std::vector<uint64_t> allocated;  // blocks within 16 cm of the room's walls
  std::vector<uint64_t> queries;    // blocks crossed by 20k rays, in ray order
};

const Workload& workload() {
  static const Workload w = [] {
    Workload result;
    const Eigen::Vector3f lo(-3, -2, 0), hi(3, 2, 3);
    const GridIndex blo = gridIndexFromPoint(lo, 1 / kBlockSize) - GridIndex::Ones();
    const GridIndex bhi = gridIndexFromPoint(hi, 1 / kBlockSize) + GridIndex::Ones();
    for (int x = blo.x(); x <= bhi.x(); ++x) {
      for (int y = blo.y(); y <= bhi.y(); ++y) {
        for (int z = blo.z(); z <= bhi.z(); ++z)
          result.allocated.push_back(packGridIndex({x, y, z}));
      }
    }
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> unit(0.0f, 1.0f);
    for (int r = 0; r < 20000; ++r) {
      const Eigen::Vector3f a =
          lo + Eigen::Vector3f(unit(rng), unit(rng), unit(rng)).cwiseProduct(hi - lo);
      // A wall point: one coordinate pinned to a face of the room.
      Eigen::Vector3f b =
          lo + Eigen::Vector3f(unit(rng), unit(rng), unit(rng)).cwiseProduct(hi - lo);
      const int axis = r % 3;
      b[axis] = (r / 3) % 2 ? hi[axis] : lo[axis];
      for (GridRayTraversal t(a / kBlockSize, b / kBlockSize);;) {
        result.queries.push_back(packGridIndex(t.cell()));
        if (!t.advance()) break;
      }
    }
    return result;
  }();
  return w;
}

template <typename Map>
void BM_BlockLookup(benchmark::State& state) {
  const Workload& w = workload();
  Map map;
  for (const uint64_t key : w.allocated) map[key] = reinterpret_cast<void*>(key);
  size_t hits = 0;
  for (auto _ : state) {
    for (const uint64_t key : w.queries) hits += map.find(key) != map.end() ? 1 : 0;
  }
  benchmark::DoNotOptimize(hits);
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations() * w.queries.size()));
  state.counters["blocks"] = static_cast<double>(w.allocated.size());
  state.counters["hit_rate"] =
      static_cast<double>(hits) / static_cast<double>(state.iterations() * w.queries.size());
}

template <typename Map>
void BM_BlockInsert(benchmark::State& state) {
  const Workload& w = workload();
  for (auto _ : state) {
    Map map;
    for (const uint64_t key : w.allocated) map.try_emplace(key, reinterpret_cast<void*>(key));
    benchmark::DoNotOptimize(map);
  }
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations() * w.allocated.size()));
}

using AbslMap = absl::flat_hash_map<uint64_t, void*>;
using StdMap = std::unordered_map<uint64_t, void*>;
BENCHMARK(BM_BlockLookup<AbslMap>)->Name("lookup/absl::flat_hash_map");
BENCHMARK(BM_BlockLookup<StdMap>)->Name("lookup/std::unordered_map");
BENCHMARK(BM_BlockInsert<AbslMap>)->Name("insert/absl::flat_hash_map");
BENCHMARK(BM_BlockInsert<StdMap>)->Name("insert/std::unordered_map");

}  // namespace
}  // namespace cblox

BENCHMARK_MAIN();
