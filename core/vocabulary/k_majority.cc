#include "core/vocabulary/k_majority.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace cblox {

void BitMajority::add(const OrbDescriptor& d) {
  for (size_t w = 0; w < 4; ++w) {
    uint64_t carry = d.words[w];
    for (int p = 0; carry != 0 && p < kPlanes; ++p) {
      const uint64_t sum = planes_[w][p] ^ carry;
      carry &= planes_[w][p];
      planes_[w][p] = sum;
      used_planes_ = std::max(used_planes_, p + 1);
    }
  }
  ++count_;
}

OrbDescriptor BitMajority::majority() const {
  OrbDescriptor result;
  for (size_t w = 0; w < 4; ++w) {
    uint64_t bits = 0;
    for (int b = 0; b < 64; ++b) {
      uint64_t ones = 0;
      for (int p = 0; p < used_planes_; ++p) ones |= ((planes_[w][p] >> b) & 1u) << p;
      if (2 * ones > count_) bits |= uint64_t{1} << b;
    }
    result.words[w] = bits;
  }
  return result;
}

void BitMajority::clear() {
  for (auto& word_planes : planes_) std::fill(std::begin(word_planes), std::end(word_planes), 0);
  used_planes_ = 0;
  count_ = 0;
}

namespace {

/// Uniform in [0, 1) from the generator's raw output (portable, unlike the distributions).
double uniform01(std::mt19937_64& rng) { return static_cast<double>(rng() >> 11) * 0x1.0p-53; }

/// A descriptor index drawn with probability proportional to weights[i] (total > 0).
size_t drawWeighted(const std::vector<double>& weights, double total, std::mt19937_64& rng) {
  const double target = uniform01(rng) * total;
  double cumulative = 0.0;
  for (size_t i = 0; i < weights.size(); ++i) {
    cumulative += weights[i];
    if (weights[i] > 0.0 && cumulative > target) return i;
  }
  for (size_t i = weights.size(); i-- > 0;) {  // rounding at the end of the sum
    if (weights[i] > 0.0) return i;
  }
  return 0;
}

/// Greedy k-means++ seeding (Arthur & Vassilvitskii 2007, with the local trials of
/// scikit-learn): each next centre is the best of 2 + floor(ln k) candidates drawn with
/// probability proportional to the squared distance to the nearest chosen centre (best =
/// smallest resulting sum of squared distances). Returns between 1 and k centres (n >= 1).
std::vector<OrbDescriptor> seedCentres(const std::vector<OrbDescriptor>& descriptors, int k,
                                       std::mt19937_64& rng) {
  const size_t n = descriptors.size();
  const int trials = 2 + static_cast<int>(std::log(static_cast<double>(k)));
  std::vector<OrbDescriptor> centres;
  centres.push_back(descriptors[static_cast<size_t>(uniform01(rng) * static_cast<double>(n))]);
  std::vector<double> squared(n), candidate_squared(n), best_squared(n);
  double total = 0.0;
  for (size_t i = 0; i < n; ++i) {
    const double d = hammingDistance(descriptors[i], centres[0]);
    squared[i] = d * d;
    total += squared[i];
  }
  while (static_cast<int>(centres.size()) < k && total > 0.0) {
    size_t best = n;
    double best_total = 0.0;
    for (int t = 0; t < trials; ++t) {
      const size_t candidate = drawWeighted(squared, total, rng);
      double candidate_total = 0.0;
      for (size_t i = 0; i < n; ++i) {
        const double d = hammingDistance(descriptors[i], descriptors[candidate]);
        candidate_squared[i] = std::min(squared[i], d * d);
        candidate_total += candidate_squared[i];
      }
      if (best == n || candidate_total < best_total) {
        best = candidate;
        best_total = candidate_total;
        std::swap(best_squared, candidate_squared);
      }
    }
    centres.push_back(descriptors[best]);
    std::swap(squared, best_squared);
    total = best_total;  // 0 when every descriptor coincides with a centre
  }
  return centres;
}

/// Nearest centre of every descriptor (ties: lowest index) and its distance; returns whether
/// any assignment changed.
bool assign(const std::vector<OrbDescriptor>& descriptors,
            const std::vector<OrbDescriptor>& centres, std::vector<uint32_t>* assignment,
            std::vector<int>* distance) {
  bool changed = false;
  for (size_t i = 0; i < descriptors.size(); ++i) {
    int best = std::numeric_limits<int>::max();
    uint32_t best_index = 0;
    for (size_t c = 0; c < centres.size(); ++c) {
      const int d = hammingDistance(descriptors[i], centres[c]);
      if (d < best) {
        best = d;
        best_index = static_cast<uint32_t>(c);
      }
    }
    changed = changed || (*assignment)[i] != best_index;
    (*assignment)[i] = best_index;
    (*distance)[i] = best;
  }
  return changed;
}

/// Majority of the members of each cluster. A cluster left without members is moved onto the
/// descriptor farthest from its own centre (in a cluster of several), the usual repair that
/// keeps k clusters when two seeds fell into one natural cluster.
void updateCentres(const std::vector<OrbDescriptor>& descriptors,
                   const std::vector<uint32_t>& assignment, std::vector<int> distance,
                   std::vector<OrbDescriptor>* centres) {
  std::vector<BitMajority> votes(centres->size());
  for (size_t i = 0; i < descriptors.size(); ++i) votes[assignment[i]].add(descriptors[i]);
  for (size_t c = 0; c < centres->size(); ++c) {
    if (votes[c].count() > 0) {
      (*centres)[c] = votes[c].majority();
      continue;
    }
    size_t farthest = descriptors.size();
    for (size_t i = 0; i < descriptors.size(); ++i) {
      if (votes[assignment[i]].count() < 2 || distance[i] <= 0) continue;
      if (farthest == descriptors.size() || distance[i] > distance[farthest]) farthest = i;
    }
    if (farthest == descriptors.size()) continue;  // nothing to move onto: stays empty
    (*centres)[c] = descriptors[farthest];
    distance[farthest] = 0;  // not again for the next empty cluster
  }
}

}  // namespace

KMajorityResult kMajorityCluster(const std::vector<OrbDescriptor>& descriptors, int k,
                                 int max_iterations, std::mt19937_64& rng) {
  if (k < 1)
    throw std::invalid_argument("kMajorityCluster: k must be >= 1, got " + std::to_string(k));
  if (max_iterations < 1) {
    throw std::invalid_argument("kMajorityCluster: max_iterations must be >= 1, got " +
                                std::to_string(max_iterations));
  }
  KMajorityResult result;
  if (descriptors.empty()) {
    result.converged = true;
    return result;
  }
  std::vector<OrbDescriptor> centres = seedCentres(descriptors, k, rng);
  std::vector<uint32_t> assignment(descriptors.size(), std::numeric_limits<uint32_t>::max());
  std::vector<int> distance(descriptors.size(), 0);
  assign(descriptors, centres, &assignment, &distance);
  result.iterations = 1;
  while (result.iterations < max_iterations) {
    updateCentres(descriptors, assignment, distance, &centres);
    ++result.iterations;
    if (!assign(descriptors, centres, &assignment, &distance)) {
      result.converged = true;
      break;
    }
  }
  if (!result.converged) {
    // Centres must be the majority of their members and members nearest to their centre.
    updateCentres(descriptors, assignment, distance, &centres);
    assign(descriptors, centres, &assignment, &distance);
  }
  // Drop empty clusters; removing a centre nobody chose changes no nearest-lowest-index pick.
  std::vector<uint32_t> members(centres.size(), 0);
  for (const uint32_t a : assignment) ++members[a];
  std::vector<uint32_t> new_index(centres.size(), 0);
  for (size_t c = 0; c < centres.size(); ++c) {
    if (members[c] == 0) continue;
    new_index[c] = static_cast<uint32_t>(result.centres.size());
    result.centres.push_back(centres[c]);
  }
  for (uint32_t& a : assignment) a = new_index[a];
  result.assignment = std::move(assignment);
  return result;
}

}  // namespace cblox
