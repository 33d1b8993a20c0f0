#include "core/integrator/depth_groups.h"

#include <algorithm>
#include <random>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

namespace cblox {
namespace {

using Groups = std::vector<std::pair<float, float>>;

// The definition: sort, split where neighbours are more than `gap` apart.
Groups sortedGroups(std::vector<float> depths, float gap) {
  std::sort(depths.begin(), depths.end());
  Groups groups{{depths[0], depths[0]}};
  for (size_t i = 1; i < depths.size(); ++i) {
    if (depths[i] - depths[i - 1] > gap) {
      groups.push_back({depths[i], depths[i]});
    } else {
      groups.back().second = depths[i];
    }
  }
  return groups;
}

Groups groupsOf(std::vector<float> depths, float gap) {
  const auto [lo, hi] = std::minmax_element(depths.begin(), depths.end());
  Groups groups;
  forEachDepthGroup(depths.data(), static_cast<int>(depths.size()), *lo, *hi, gap,
                    [&](float first, float last) {
                      groups.push_back({first, last});
                    });
  return groups;
}

// Random cells of up to 64 depths on one to four surfaces, with spans below 127 half gaps
// (buckets) and above (sorted): the same groups, bit for bit, as sorting.
TEST(DepthGroups, SameGroupsAsSortingTheDepths) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  size_t split_cells = 0;
  for (int cell = 0; cell < 20000; ++cell) {
    const float gap = cell % 10 == 0 ? 0.005f : 0.08f;  // 1 in 10 wider than the buckets
    const int surfaces = 1 + static_cast<int>(unit(rng) * 4.0f);
    std::vector<float> centres;
    for (int s = 0; s < surfaces; ++s) centres.push_back(0.3f + 3.7f * unit(rng));
    std::vector<float> depths(1 + static_cast<size_t>(unit(rng) * 64.0f));
    for (float& d : depths) {
      d = centres[static_cast<size_t>(unit(rng) * static_cast<float>(surfaces)) % centres.size()] +
          0.1f * unit(rng);
    }
    const Groups expected = sortedGroups(depths, gap);
    if (expected.size() > 1) ++split_cells;
    ASSERT_EQ(groupsOf(depths, gap), expected) << "cell " << cell;
  }
  EXPECT_GT(split_cells, 5000u);
}

// Gaps of exactly `gap` join, gaps just over it split; bucket edges do not split a group.
TEST(DepthGroups, SplitsOnlyWhereTheGapIsExceeded) {
  const float gap = 0.25f;  // exact in binary, as are the depths below
  EXPECT_EQ(groupsOf({1.0f, 1.25f, 1.5f, 1.75f}, gap), (Groups{{1.0f, 1.75f}}));
  EXPECT_EQ(groupsOf({1.75f, 1.0f, 1.5f + 0.001f}, gap), (Groups{{1.0f, 1.0f}, {1.501f, 1.75f}}));
  EXPECT_EQ(groupsOf({2.0f}, gap), (Groups{{2.0f, 2.0f}}));
  EXPECT_EQ(groupsOf({2.0f, 2.0f, 2.0f}, gap), (Groups{{2.0f, 2.0f}}));
  // 200 half gaps: sorted, the same rule.
  EXPECT_EQ(groupsOf({1.0f, 26.0f, 1.2f, 25.9f}, gap), (Groups{{1.0f, 1.2f}, {25.9f, 26.0f}}));
}

}  // namespace
}  // namespace cblox
