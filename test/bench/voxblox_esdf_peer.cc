#include "test/bench/voxblox_esdf_peer.h"

#include <chrono>
#include <unordered_map>

#include <voxblox/core/block.h>
#include <voxblox/core/layer.h>
#include <voxblox/core/voxel.h>
#include <voxblox/integrator/esdf_integrator.h>

#include "test/bench/bench_stats.h"

namespace cblox::bench {

struct VoxbloxEsdfPeer::Impl {
  Impl(const LayerConfig& geometry, const voxblox::EsdfIntegrator::Config& config)
      : esdf_config(config),
        tsdf(geometry.voxel_size, static_cast<size_t>(geometry.voxels_per_side)),
        esdf(geometry.voxel_size, static_cast<size_t>(geometry.voxels_per_side)),
        integrator(config, &tsdf, &esdf) {}

  voxblox::EsdfIntegrator::Config esdf_config;
  voxblox::Layer<voxblox::TsdfVoxel> tsdf;
  voxblox::Layer<voxblox::EsdfVoxel> esdf;
  voxblox::EsdfIntegrator integrator;
  std::unordered_map<uint64_t, uint64_t> copied;  // our block key -> changeCount copied
};

VoxbloxEsdfPeer::VoxbloxEsdfPeer(const LayerConfig& geometry, float max_distance_m,
                                 float min_distance_m, bool full_euclidean) {
  voxblox::EsdfIntegrator::Config config;
  config.full_euclidean_distance = full_euclidean;
  config.max_distance_m = max_distance_m;
  config.default_distance_m = max_distance_m;
  config.min_distance_m = min_distance_m;
  impl_ = std::make_unique<Impl>(geometry, config);
}

VoxbloxEsdfPeer::~VoxbloxEsdfPeer() = default;

double VoxbloxEsdfPeer::update(const TsdfLayer& tsdf) {
  const int n = tsdf.voxelsPerSide();
  for (const auto& [key, block] : tsdf.blocks()) {
    const uint64_t count = block->changeCount();
    const auto it = impl_->copied.find(key);
    if (it != impl_->copied.end() && it->second == count) continue;
    impl_->copied[key] = count;
    const BlockIndex& b = block->index();
    voxblox::Block<voxblox::TsdfVoxel>::Ptr to =
        impl_->tsdf.allocateBlockPtrByIndex(voxblox::BlockIndex(b.x(), b.y(), b.z()));
    // Both number a block's voxels x fastest, then y, then z.
    for (int linear = 0; linear < n * n * n; ++linear) {
      const TsdfVoxel& v = block->voxel(linear);
      voxblox::TsdfVoxel& w = to->getVoxelByLinearIndex(static_cast<size_t>(linear));
      w.distance = v.distance;
      w.weight = v.weight;
    }
    to->set_has_data(true);
    to->updated().set(voxblox::Update::kEsdf);
  }
  const auto start = std::chrono::steady_clock::now();
  impl_->integrator.updateFromTsdfLayer(true);
  return msSince(start);
}

double VoxbloxEsdfPeer::batch() {
  voxblox::Layer<voxblox::EsdfVoxel> fresh(impl_->tsdf.voxel_size(),
                                          impl_->tsdf.voxels_per_side());
  voxblox::EsdfIntegrator integrator(impl_->esdf_config, &impl_->tsdf, &fresh);
  const auto start = std::chrono::steady_clock::now();
  integrator.updateFromTsdfLayerBatch();
  return msSince(start);
}

bool VoxbloxEsdfPeer::distance(const GlobalVoxelIndex& index, float* distance) const {
  const voxblox::EsdfVoxel* v =
      impl_->esdf.getVoxelPtrByGlobalIndex(voxblox::GlobalIndex(index.x(), index.y(), index.z()));
  if (v == nullptr || !v->observed) return false;
  *distance = v->distance;
  return true;
}

}  // namespace cblox::bench
