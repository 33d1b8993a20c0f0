#include "core/maintenance/covisibility_graph.h"

#include <map>
#include <random>
#include <set>
#include <vector>

#include <gtest/gtest.h>

namespace cblox {
namespace {

std::vector<uint64_t> range(uint64_t begin, uint64_t end) {
  std::vector<uint64_t> ids;
  for (uint64_t i = begin; i < end; ++i) ids.push_back(i);
  return ids;
}

TEST(CovisibilityGraphTest, WeightsAreTheSizesOfTheIntersections) {
  SubvolumeCovisibilityGraph g;
  EXPECT_EQ(g.addLandmarks(1, range(0, 100)), 100u);
  EXPECT_EQ(g.addLandmarks(2, range(60, 200)), 140u);
  EXPECT_EQ(g.addLandmarks(3, range(190, 300)), 110u);
  EXPECT_EQ(g.weight(1, 2), 40);
  EXPECT_EQ(g.weight(2, 1), 40);
  EXPECT_EQ(g.weight(2, 3), 10);
  EXPECT_EQ(g.weight(1, 3), 0);
  EXPECT_EQ(g.weight(1, 1), 0);
  EXPECT_EQ(g.numEdges(), 2u);
  // Landmarks already held (and repeats within one call) change nothing.
  const std::vector<uint64_t> again{5, 5, 61, 61};
  EXPECT_EQ(g.addLandmarks(1, again), 0u);
  EXPECT_EQ(g.weight(1, 2), 40);
  EXPECT_EQ(g.numLandmarks(1), 100u);
  // A new landmark seen by 1 and 3 adds an edge.
  const std::vector<uint64_t> shared{1000};
  g.addLandmarks(1, shared);
  g.addLandmarks(3, shared);
  EXPECT_EQ(g.weight(1, 3), 1);
  EXPECT_EQ(g.neighbours(1), (std::vector<std::pair<int64_t, int>>{{2, 40}, {3, 1}}));
}

TEST(CovisibilityGraphTest, MergeTakesTheUnionAndDropsTheAbsorbedVertex) {
  SubvolumeCovisibilityGraph g;
  g.addLandmarks(1, range(0, 100));
  g.addLandmarks(2, range(60, 200));
  g.addLandmarks(3, range(150, 300));
  ASSERT_TRUE(g.merge(1, 2));
  EXPECT_FALSE(g.contains(2));
  EXPECT_EQ(g.numLandmarks(1), 200u);  // [0, 200)
  EXPECT_EQ(g.weight(1, 3), 50);       // [150, 200)
  EXPECT_EQ(g.weight(1, 2), 0);
  EXPECT_EQ(g.numEdges(), 1u);
  EXPECT_FALSE(g.merge(1, 2));  // absorbed already
  EXPECT_FALSE(g.merge(1, 1));
  EXPECT_FALSE(g.merge(9, 3));
  EXPECT_TRUE(g.removeSubvolume(3));
  EXPECT_FALSE(g.removeSubvolume(3));
  EXPECT_EQ(g.numEdges(), 0u);
  EXPECT_EQ(g.numSubvolumes(), 1u);
}

// Random keyframe arrivals, fusions and removals: every weight always equals the
// brute-force intersection of the sets.
TEST(CovisibilityGraphTest, IncrementalWeightsMatchBruteForceUnderRandomOperations) {
  std::mt19937 rng(3);
  SubvolumeCovisibilityGraph g;
  std::map<int64_t, std::set<uint64_t>> truth;
  int64_t next_id = 0;
  for (int step = 0; step < 400; ++step) {
    const int op = static_cast<int>(rng() % 10);
    if (op < 7 || truth.size() < 2) {
      // A keyframe: landmarks drawn around a moving window, as a camera sees them.
      const int64_t s = truth.empty() || rng() % 4 == 0
                            ? next_id++
                            : std::next(truth.begin(), rng() % truth.size())->first;
      std::vector<uint64_t> ids;
      const uint64_t centre = static_cast<uint64_t>(step) * 5;
      for (int k = 0; k < 40; ++k) ids.push_back(centre + rng() % 120);
      g.addLandmarks(s, ids);
      truth[s].insert(ids.begin(), ids.end());
    } else if (op < 9) {
      auto a = std::next(truth.begin(), rng() % truth.size());
      auto b = std::next(truth.begin(), rng() % truth.size());
      if (a == b) continue;
      ASSERT_TRUE(g.merge(a->first, b->first));
      a->second.insert(b->second.begin(), b->second.end());
      truth.erase(b);
    } else {
      auto a = std::next(truth.begin(), rng() % truth.size());
      ASSERT_TRUE(g.removeSubvolume(a->first));
      truth.erase(a);
    }
    size_t edges = 0;
    for (const auto& [i, li] : truth) {
      ASSERT_EQ(g.numLandmarks(i), li.size());
      for (const auto& [j, lj] : truth) {
        if (j <= i) continue;
        int shared = 0;
        for (const uint64_t l : li) shared += lj.count(l) ? 1 : 0;
        ASSERT_EQ(g.weight(i, j), shared) << "step " << step << " pair " << i << "," << j;
        edges += shared > 0 ? 1 : 0;
      }
    }
    ASSERT_EQ(g.numEdges(), edges) << "step " << step;
    ASSERT_EQ(g.numSubvolumes(), truth.size());
  }
}

TEST(CovisibilityGraphTest, CandidatesMeetBothBoundsAndComeStrongestFirst) {
  SubvolumeCovisibilityGraph g;
  g.addLandmarks(1, range(0, 100));
  g.addLandmarks(2, range(50, 150));     // shares 50 with 1
  g.addLandmarks(3, range(140, 1140));   // shares 10 with 2, 0 with 1
  g.addLandmarks(4, range(1100, 1140));  // shares 40 with 3: 100 % of its 40
  CovisibilityGraphConfig config;
  config.min_shared_landmarks = 30;
  config.min_shared_ratio = 0.3;
  std::vector<CovisibilityCandidate> c = g.candidates(config);
  ASSERT_EQ(c.size(), 2u);
  EXPECT_EQ(c[0].a, 1);
  EXPECT_EQ(c[0].b, 2);
  EXPECT_EQ(c[0].shared, 50);
  EXPECT_EQ(c[0].landmarks_a, 100u);
  EXPECT_EQ(c[0].landmarks_b, 100u);
  EXPECT_EQ(c[1].a, 3);
  EXPECT_EQ(c[1].b, 4);
  EXPECT_EQ(c[1].shared, 40);
  // The relative bound: 50 shared of 100 is 0.5 < 0.6; 40 of min(1000, 40) is 1.0.
  config.min_shared_ratio = 0.6;
  c = g.candidates(config);
  ASSERT_EQ(c.size(), 1u);
  EXPECT_EQ(c[0].a, 3);
  // The absolute bound alone.
  config.min_shared_ratio = 0.0;
  config.min_shared_landmarks = 10;
  EXPECT_EQ(g.candidates(config).size(), 3u);
}

TEST(CovisibilityGraphTest, ConfigValidationNamesTheField) {
  EXPECT_EQ(CovisibilityGraphConfig{}.validate(), "");
  CovisibilityGraphConfig c;
  c.min_shared_landmarks = 0;
  EXPECT_NE(c.validate().find("min_shared_landmarks"), std::string::npos);
  c = CovisibilityGraphConfig{};
  c.min_shared_ratio = 1.5;
  EXPECT_NE(c.validate().find("min_shared_ratio"), std::string::npos);
}

}  // namespace
}  // namespace cblox
