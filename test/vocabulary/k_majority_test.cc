#include "core/vocabulary/k_majority.h"

#include <algorithm>
#include <set>

#include <gtest/gtest.h>

#include "test/vocabulary/synthetic_descriptors.h"

namespace cblox {
namespace {

using test::makeClusteredData;
using test::randomDescriptor;

TEST(BitMajorityTest, MatchesANaiveBitCountIncludingTies) {
  std::mt19937_64 rng(3);
  for (const int n : {1, 2, 3, 4, 7, 64, 255, 1000}) {
    std::vector<OrbDescriptor> ds;
    BitMajority majority;
    for (int i = 0; i < n; ++i) {
      ds.push_back(randomDescriptor(rng));
      majority.add(ds.back());
    }
    EXPECT_EQ(majority.count(), static_cast<uint64_t>(n));
    const OrbDescriptor m = majority.majority();
    for (int bit = 0; bit < 256; ++bit) {
      int ones = 0;
      for (const OrbDescriptor& d : ds) ones += d.bit(bit);
      ASSERT_EQ(m.bit(bit), 2 * ones > n) << "n " << n << " bit " << bit;
    }
  }
  // Exact tie: one all-ones and one all-zero descriptor give zero.
  BitMajority tie;
  OrbDescriptor ones;
  ones.words.fill(~uint64_t{0});
  tie.add(ones);
  tie.add(OrbDescriptor{});
  EXPECT_EQ(tie.majority(), OrbDescriptor{});
  tie.add(ones);
  EXPECT_EQ(tie.majority(), ones);
  tie.clear();
  EXPECT_EQ(tie.count(), 0u);
  EXPECT_EQ(tie.majority(), OrbDescriptor{});
}

TEST(KMajorityTest, RecoversTheCentresOfClusteredDataAndAssignsEveryMember) {
  // 10 random centres (pairwise ~128 bits apart), 30 members each with 12 flipped bits.
  const test::ClusteredData data = makeClusteredData(10, 30, 12, 42);
  std::mt19937_64 rng(7);
  const KMajorityResult result = kMajorityCluster(data.members, 10, 20, rng);
  EXPECT_TRUE(result.converged);
  ASSERT_EQ(result.centres.size(), 10u);
  ASSERT_EQ(result.assignment.size(), data.members.size());
  // Every found centre is exactly one of the true centres, each found once.
  std::vector<int> true_of_found(10, -1);
  for (size_t f = 0; f < 10; ++f) {
    for (size_t c = 0; c < 10; ++c) {
      if (result.centres[f] == data.centres[c]) true_of_found[f] = static_cast<int>(c);
    }
    ASSERT_GE(true_of_found[f], 0) << "found centre " << f << " is not a true centre";
  }
  EXPECT_EQ(std::set<int>(true_of_found.begin(), true_of_found.end()).size(), 10u);
  for (size_t i = 0; i < data.members.size(); ++i) {
    EXPECT_EQ(true_of_found[result.assignment[i]], data.centre_of[i]) << "member " << i;
  }
}

TEST(KMajorityTest, FewerDistinctDescriptorsThanKGiveOneClusterEach) {
  std::mt19937_64 rng(1);
  const OrbDescriptor a = randomDescriptor(rng), b = randomDescriptor(rng);
  const std::vector<OrbDescriptor> data{a, b, a, a, b};
  const KMajorityResult result = kMajorityCluster(data, 10, 10, rng);
  ASSERT_EQ(result.centres.size(), 2u);
  EXPECT_TRUE(result.converged);
  for (size_t i = 0; i < data.size(); ++i) {
    EXPECT_EQ(result.centres[result.assignment[i]], data[i]);
  }
  // Identical descriptors: one cluster.
  const KMajorityResult same = kMajorityCluster({a, a, a}, 4, 10, rng);
  ASSERT_EQ(same.centres.size(), 1u);
  EXPECT_EQ(same.centres[0], a);
  EXPECT_TRUE(kMajorityCluster({}, 4, 10, rng).centres.empty());
}

TEST(KMajorityTest, IterationLimitStillGivesNearestCentreAssignmentsAndRejectsBadArguments) {
  std::mt19937_64 rng(5);
  std::vector<OrbDescriptor> data;
  for (int i = 0; i < 300; ++i) data.push_back(randomDescriptor(rng));  // no structure
  const KMajorityResult result = kMajorityCluster(data, 8, 1, rng);
  EXPECT_EQ(result.iterations, 1);
  EXPECT_FALSE(result.converged);
  for (size_t i = 0; i < data.size(); ++i) {
    const int assigned = hammingDistance(data[i], result.centres[result.assignment[i]]);
    for (const OrbDescriptor& c : result.centres) ASSERT_LE(assigned, hammingDistance(data[i], c));
  }
  EXPECT_THROW(kMajorityCluster(data, 0, 10, rng), std::invalid_argument);
  EXPECT_THROW(kMajorityCluster(data, 3, 0, rng), std::invalid_argument);
}

}  // namespace
}  // namespace cblox
