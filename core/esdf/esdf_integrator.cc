#include "core/esdf/esdf_integrator.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace cblox {
namespace {

// Queue keys are distances in 1/kKeySteps voxel.
constexpr float kKeySteps = 8.0f;
// A site's value is taken again once it grew by more than 1/kGrowSteps voxel.
constexpr float kGrowSteps = 2.0f;
// Free voxels whose TSDF distance is below this many voxels may be sites.
constexpr float kSiteTsdfVoxels = 4.0f;
// Entries' worth of queue storage kept between waves (over all buckets).
constexpr size_t kKeepQueueEntries = size_t{1} << 14;

Eigen::Vector3i siteOf(const EsdfVoxel& v) { return {v.site[0], v.site[1], v.site[2]}; }

void setSite(EsdfVoxel* v, const Eigen::Vector3i& offset) {
  v->site[0] = static_cast<int16_t>(offset.x());
  v->site[1] = static_cast<int16_t>(offset.y());
  v->site[2] = static_cast<int16_t>(offset.z());
  v->flags = static_cast<uint8_t>(v->flags | EsdfVoxel::kHasSite);
}

}  // namespace

EsdfIntegrator::EsdfIntegrator(const EsdfConfig& config) : config_(config) {
  if (const std::string e = config.validate(); !e.empty()) throw std::invalid_argument(e);
  for (int z = -1; z <= 1; ++z) {
    for (int y = -1; y <= 1; ++y) {
      for (int x = -1; x <= 1; ++x) {
        if (x != 0 || y != 0 || z != 0) neighbours_.emplace_back(x, y, z);
      }
    }
  }
}

void EsdfIntegrator::prepare(const EsdfLayer& esdf) {
  if (esdf.maxDistance() != config_.max_distance_m) {
    throw std::invalid_argument("the distance field's max distance differs from the config's");
  }
  const double reach = static_cast<double>(config_.max_distance_m) / esdf.voxelSize() + 2.0;
  if (reach > 30000.0) {
    throw std::invalid_argument("max_distance_m spans more than 30000 voxels");
  }
  voxel_size_ = esdf.voxelSize();
  voxels_per_side_ = esdf.voxelsPerSide();
  voxels_per_side_log2_ = esdf.voxelsPerSideLog2();
  neighbour_linear_.clear();
  for (const GridIndex& d : neighbours_) {
    neighbour_linear_.push_back(d.x() + voxels_per_side_ * (d.y() + voxels_per_side_ * d.z()));
  }
  // A site is carried one voxel past the cap, so that voxels at the cap know they are there.
  max_reach_ = config_.max_distance_m + voxel_size_;
  const auto max_key = static_cast<uint32_t>(std::ceil(reach * kKeySteps));
  // Centre distances of every offset a wave can carry, by squared length in voxels.
  const auto max_sq = static_cast<size_t>(std::ceil((reach + 1.0) * (reach + 1.0)));
  if (centre_distance_.size() != max_sq + 1 || centre_distance_voxel_ != voxel_size_) {
    centre_distance_.resize(max_sq + 1);
    for (size_t i = 0; i <= max_sq; ++i) {
      centre_distance_[i] = std::sqrt(static_cast<float>(i)) * voxel_size_;
    }
    centre_distance_voxel_ = voxel_size_;
  }
  if (max_key != max_key_) {
    max_key_ = max_key;
    queue_ = DistanceBucketQueue<Entry>(max_key_);
  }
}

uint32_t EsdfIntegrator::keyOf(float distance) const {
  const float steps = std::max(0.0f, distance) / voxel_size_ * kKeySteps;
  return steps >= static_cast<float>(max_key_) ? max_key_ : static_cast<uint32_t>(steps);
}

const EsdfVoxel* EsdfIntegrator::siteAt(const EsdfLayer& esdf, const EsdfBlock& block,
                                        const GridIndex& local,
                                        const Eigen::Vector3i& offset) const {
  const GridIndex n = local + offset;
  // The site's block relative to `block` (arithmetic shifts: -1 below, 1 above); within one
  // block of it, through the neighbour pointers.
  const GridIndex b(n.x() >> voxels_per_side_log2_, n.y() >> voxels_per_side_log2_,
                    n.z() >> voxels_per_side_log2_);
  const EsdfVoxel* v = nullptr;
  if ((b.array().abs() <= 1).all()) {
    const EsdfBlock* other =
        block.neighbours[static_cast<size_t>(EsdfBlock::neighbourSlot(b.x(), b.y(), b.z()))];
    const int mask = voxels_per_side_ - 1;
    if (other != nullptr) {
      v = &other->voxel(esdf.linearIndex(GridIndex(n.x() & mask, n.y() & mask, n.z() & mask)));
    }
  } else {
    v = esdf.getVoxel(block.index * voxels_per_side_ + n);
  }
  return v != nullptr && v->isSite() ? v : nullptr;
}

bool EsdfIntegrator::stale(const EsdfLayer& esdf, const VoxelRef& ref,
                           const EsdfVoxel& voxel) const {
  const Eigen::Vector3i offset = siteOf(voxel);
  const EsdfVoxel* site = siteAt(esdf, *ref.block, ref.local, offset);
  if (site == nullptr) return true;
  const auto sq = static_cast<size_t>(offset.squaredNorm());
  if (sq >= centre_distance_.size()) return false;
  // The wave's own formula, so that a voxel computed from the site's current value is equal.
  return voxel.own_distance <
         std::max(0.0f, centre_distance_[sq] + siteDistance(site->own_distance));
}

float EsdfIntegrator::gradientNorm(const Block& tsdf, int linear) const {
  const int last = voxels_per_side_ - 1;
  const int local[3] = {linear & last, (linear >> voxels_per_side_log2_) & last,
                        linear >> (2 * voxels_per_side_log2_)};
  const auto observed = [this](const TsdfVoxel& t) {
    return t.weight > 0.0f && t.weight >= config_.min_weight;
  };
  const float centre = tsdf.voxel(linear).distance;
  float sq = 0.0f;
  int step = 1;
  for (int a = 0; a < 3; ++a, step <<= voxels_per_side_log2_) {
    // Central difference inside the block, one-sided at its border or beside unobserved
    // voxels; an axis without an observed neighbour adds nothing.
    const TsdfVoxel* lo = local[a] > 0 ? &tsdf.voxel(linear - step) : nullptr;
    const TsdfVoxel* hi = local[a] < last ? &tsdf.voxel(linear + step) : nullptr;
    if (lo != nullptr && !observed(*lo)) lo = nullptr;
    if (hi != nullptr && !observed(*hi)) hi = nullptr;
    float derivative = 0.0f;
    if (lo != nullptr && hi != nullptr) {
      derivative = 0.5f * (hi->distance - lo->distance);
    } else if (hi != nullptr) {
      derivative = hi->distance - centre;
    } else if (lo != nullptr) {
      derivative = centre - lo->distance;
    }
    sq += derivative * derivative;
  }
  return std::max(1.0f, std::sqrt(sq) / voxel_size_);
}

void EsdfIntegrator::readBlock(EsdfLayer* esdf, EsdfBlock* block, EsdfUpdateStats* stats) {
  const Block& tsdf = *block->tsdf;
  EsdfVoxel* const voxels = block->mutableVoxels();
  for (int linear = 0; linear < esdf->voxelsPerBlock(); ++linear) {
    const TsdfVoxel& t = tsdf.voxel(linear);
    EsdfVoxel& v = voxels[linear];
    const bool observed = t.weight > 0.0f && t.weight >= config_.min_weight;
    v.state = !observed            ? VoxelState::kUnknown
              : t.distance <= 0.0f ? VoxelState::kOccupied
                                   : VoxelState::kFree;
    // A free voxel up to kSiteTsdfVoxels from the surface is a site when its value (TSDF
    // distance over the gradient's norm) is below one voxel.
    float value = t.distance;
    if (observed && t.distance > 0.0f && t.distance < kSiteTsdfVoxels * voxel_size_) {
      value = t.distance / gradientNorm(tsdf, linear);
    }
    if (observed && value < voxel_size_) {
      if (!v.isSite()) {
        v.flags = EsdfVoxel::kSite;
        setSite(&v, Eigen::Vector3i::Zero());
        push(0, block, linear);
        ++stats->sites_added;
        v.own_distance = value;
      } else if ((v.own_distance - value) * kKeySteps > voxel_size_ ||
                 (value - v.own_distance) * kGrowSteps > voxel_size_ ||
                 (value <= 0.0f) != (v.own_distance <= 0.0f)) {
        // Nearer by more than a key step: its wave may now win voxels that another site
        // has. Farther by more than half a voxel: the voxels that took it were computed
        // through a nearer surface than there is now, and are raised first. A smaller move
        // that keeps its side of the surface is not taken: the site keeps the value its
        // voxels were computed with (growth is let lag further than shrinking: its voxels
        // then answer less than a rebuild would, the safe side, and a surface whose TSDF
        // settles frame by frame raises no wave each frame).
        if (siteDistance(value) > siteDistance(v.own_distance)) {
          v.flags = static_cast<uint8_t>(v.flags | EsdfVoxel::kSiteMoved);
        }
        v.own_distance = value;
        push(0, block, linear);
      }
      continue;
    }
    if (v.isSite()) {
      // The surface is gone: the raise wave clears the voxels that took it as their site.
      v.flags = EsdfVoxel::kRaise;
      push(0, block, linear);
      ++stats->sites_removed;
    } else if (v.flags == 0) {
      v.own_distance = config_.max_distance_m;
    }
  }
}

void EsdfIntegrator::seedFromNeighbours(EsdfLayer* esdf, EsdfBlock* block) {
  const int last = voxels_per_side_ - 1;
  for (const GridIndex& d : neighbours_) {
    EsdfBlock* other = esdf->getBlock(block->index + d);
    if (other == nullptr) continue;
    // The voxels of `other` that touch `block`: per axis the last layer when `other` lies
    // below, the first when above, all when level.
    GridIndex lo, hi;
    for (int a = 0; a < 3; ++a) {
      lo[a] = d[a] < 0 ? last : 0;
      hi[a] = d[a] > 0 ? 0 : last;
    }
    for (int z = lo.z(); z <= hi.z(); ++z) {
      for (int y = lo.y(); y <= hi.y(); ++y) {
        for (int x = lo.x(); x <= hi.x(); ++x) {
          const int linear = esdf->linearIndex(GridIndex(x, y, z));
          const EsdfVoxel& v = other->voxel(linear);
          if (v.hasSite() && (v.flags & EsdfVoxel::kRaise) == 0) {
            push(v.isSite() ? 0 : keyOf(v.own_distance), other, linear);
          }
        }
      }
    }
  }
}

void EsdfIntegrator::finish(EsdfLayer* esdf, EsdfUpdateStats* stats) {
  const int mask = voxels_per_side_ - 1;
  Entry entry{0, 0};
  uint32_t key = 0;
  while (!queue_.empty()) {
    queue_.pop(&entry, &key);
    ++stats->voxels_popped;
    EsdfBlock* const block = slots_[entry.slot];
    const int linear = static_cast<int>(entry.linear);
    // Read only: a write to block below may move its voxels (copy-on-write).
    const EsdfVoxel& v = block->voxel(linear);
    const GridIndex local(linear & mask, (linear >> voxels_per_side_log2_) & mask,
                          linear >> (2 * voxels_per_side_log2_));
    if ((v.flags & EsdfVoxel::kRaise) != 0) {
      // Raise: neighbours whose site is no site any more, or whose distance is below what
      // their site gives now (it moved away), join the wave; neighbours with a valid site
      // become sources of the lower wave that refills the cleared region.
      for (const GridIndex& d : neighbours_) {
        const VoxelRef n = neighbour(esdf, block, local, d);
        if (n.block == nullptr) continue;
        const EsdfVoxel& nv = n.voxel();
        if (!nv.hasSite()) continue;
        if (nv.isSite()) {
          push(0, n.block, n.linear);
          continue;
        }
        const float n_distance = nv.own_distance;
        if (stale(*esdf, n, nv)) n.mutableVoxel().flags = EsdfVoxel::kRaise;
        push(keyOf(n_distance), n.block, n.linear);
      }
      EsdfVoxel& w = block->mutableVoxels()[linear];
      w.flags = 0;
      w.own_distance = config_.max_distance_m;
      continue;
    }
    if ((v.flags & EsdfVoxel::kSiteMoved) != 0) {
      // A site whose distance grew: the neighbours that took it start a raise wave (which
      // passes on to every voxel that took it); then it spreads as any site.
      for (const GridIndex& d : neighbours_) {
        const VoxelRef n = neighbour(esdf, block, local, d);
        if (n.block == nullptr) continue;
        const EsdfVoxel& nv = n.voxel();
        if (!nv.hasSite() || nv.isSite() || siteOf(nv) + d != Eigen::Vector3i::Zero() ||
            !stale(*esdf, n, nv)) {
          continue;
        }
        const float n_distance = nv.own_distance;
        n.mutableVoxel().flags = EsdfVoxel::kRaise;
        push(keyOf(n_distance), n.block, n.linear);
      }
      EsdfVoxel& w = block->mutableVoxels()[linear];
      w.flags = static_cast<uint8_t>(w.flags & ~EsdfVoxel::kSiteMoved);
    }
    // Read again: a write above may have moved the block's voxels.
    const EsdfVoxel& u = block->voxel(linear);
    if (!u.hasSite()) continue;
    const Eigen::Vector3i site = siteOf(u);
    float site_distance = siteDistance(u.own_distance);
    if (!u.isSite()) {
      if (keyOf(u.own_distance) != key) continue;  // improved since it was queued
      const EsdfVoxel* s = siteAt(*esdf, *block, local, site);
      if (s == nullptr) continue;  // its site vanished; a raise wave is on its way
      site_distance = siteDistance(s->own_distance);
    }
    const bool interior = local.minCoeff() > 0 && local.maxCoeff() < voxels_per_side_ - 1;
    for (size_t k = 0; k < neighbours_.size(); ++k) {
      const GridIndex& d = neighbours_[k];
      VoxelRef n;
      if (interior) {  // no block border to cross (n.local is not needed below)
        n.block = block;
        n.linear = linear + neighbour_linear_[k];
      } else {
        n = neighbour(esdf, block, local, d);
        if (n.block == nullptr) continue;
      }
      const EsdfVoxel& nv = n.voxel();
      if (nv.isSite() || (nv.flags & EsdfVoxel::kRaise) != 0) continue;
      const Eigen::Vector3i offset = site - d;
      const auto sq = static_cast<size_t>(offset.squaredNorm());
      if (sq >= centre_distance_.size()) continue;
      const float through = std::max(0.0f, centre_distance_[sq] + site_distance);
      if (through > max_reach_) continue;
      if (nv.hasSite() && through >= nv.own_distance) continue;
      EsdfVoxel& w = n.mutableVoxel();
      setSite(&w, offset);
      w.own_distance = through;
      push(keyOf(through), n.block, n.linear);
    }
  }
  stats->queue_peak_bytes = queue_.peakStorageBytes();
  queue_high_water_bytes_ = std::max(queue_high_water_bytes_, stats->queue_peak_bytes);
  queue_.releaseStorage(kKeepQueueEntries);
}

size_t EsdfIntegrator::workingBytes() const {
  return queue_high_water_bytes_ + centre_distance_.capacity() * sizeof(float);
}

EsdfUpdateStats EsdfIntegrator::stage(const TsdfLayer& tsdf, EsdfLayer* esdf) {
  if (tsdf.voxelSize() != esdf->voxelSize() || tsdf.voxelsPerSide() != esdf->voxelsPerSide()) {
    throw std::invalid_argument("the TSDF and distance-field layers have different geometry");
  }
  prepare(*esdf);
  queue_.resetPeak();
  EsdfUpdateStats stats;
  std::vector<EsdfBlock*> added;    // new blocks, with a TSDF block
  std::vector<EsdfBlock*> changed;  // blocks to read again (band blocks now observed too)
  std::vector<EsdfBlock*> grown;    // blocks that have a TSDF block since this call
  for (const auto& [key, tsdf_block] : tsdf.blocks()) {
    bool fresh = false;
    EsdfBlock* block = esdf->allocateBlock(tsdf_block->index(), &fresh);
    const uint64_t count = tsdf_block->changeCount();
    if (fresh) {
      block->tsdf = tsdf_block.get();
      block->tsdf_change_count = count;
      added.push_back(block);
      grown.push_back(block);
    } else if (block->isBand()) {
      // A band block the TSDF now covers: it keeps the distances it carries.
      block->tsdf = tsdf_block.get();
      block->tsdf_change_count = count;
      changed.push_back(block);
      grown.push_back(block);
    } else if (block->tsdf != tsdf_block.get()) {
      return restage(tsdf, esdf);  // a block was removed and another allocated there
    } else if (block->tsdf_change_count != count) {
      block->tsdf_change_count = count;
      changed.push_back(block);
    }
  }
  // The band around the blocks the TSDF gained (or a band block that became observed).
  const int band = config_.band_blocks;
  std::vector<EsdfBlock*> band_added;
  for (const EsdfBlock* block : grown) {
    for (int z = -band; z <= band; ++z) {
      for (int y = -band; y <= band; ++y) {
        for (int x = -band; x <= band; ++x) {
          const BlockIndex index = block->index + BlockIndex(x, y, z);
          if (!gridIndexInRange(index)) continue;
          bool fresh = false;
          EsdfBlock* other = esdf->allocateBlock(index, &fresh);
          if (fresh) band_added.push_back(other);
        }
      }
    }
  }
  // The queue names blocks by slot (8-byte entries): number them before the first push.
  slots_.clear();
  slots_.reserve(esdf->numBlocks());
  size_t observed_blocks = 0;
  for (const auto& [key, block] : esdf->blocks()) {
    block->queue_slot = static_cast<uint32_t>(slots_.size());
    slots_.push_back(block.get());
    if (!block->isBand()) ++observed_blocks;
  }
  if (observed_blocks != tsdf.numBlocks()) return restage(tsdf, esdf);  // TSDF blocks left
  // New blocks first take the waves of their neighbours' sites (before any of them is read,
  // so only established sites are pushed), then every new or changed block is read.
  for (EsdfBlock* block : added) seedFromNeighbours(esdf, block);
  for (EsdfBlock* block : band_added) seedFromNeighbours(esdf, block);
  for (EsdfBlock* block : added) readBlock(esdf, block, &stats);
  for (EsdfBlock* block : changed) readBlock(esdf, block, &stats);
  stats.esdf_blocks_added = added.size() + band_added.size();
  stats.tsdf_blocks_read = added.size() + changed.size();
  return stats;
}

EsdfUpdateStats EsdfIntegrator::restage(const TsdfLayer& tsdf, EsdfLayer* esdf) {
  esdf->clear();
  queue_ = DistanceBucketQueue<Entry>(max_key_);
  EsdfUpdateStats stats = stage(tsdf, esdf);
  stats.rebuilt = true;
  return stats;
}

EsdfUpdateStats EsdfIntegrator::update(const TsdfLayer& tsdf, EsdfLayer* esdf) {
  EsdfUpdateStats stats = stage(tsdf, esdf);
  finish(esdf, &stats);
  return stats;
}

EsdfUpdateStats EsdfIntegrator::rebuild(const TsdfLayer& tsdf, EsdfLayer* esdf) {
  EsdfUpdateStats stats = restage(tsdf, esdf);
  finish(esdf, &stats);
  return stats;
}

}  // namespace cblox
