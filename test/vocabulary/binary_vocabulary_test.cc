#include "core/vocabulary/binary_vocabulary.h"

#include <cmath>
#include <map>
#include <numeric>
#include <set>

#include <gtest/gtest.h>

#include "test/vocabulary/synthetic_descriptors.h"

namespace cblox {
namespace {

using test::makeClusteredData;

/// Images for clustered data: image i holds the members of centres 0..i, so centre c's word
/// is in n - c of the n images.
std::vector<std::vector<OrbDescriptor>> nestedImages(const test::ClusteredData& data, int n,
                                                     int members_per_centre) {
  std::vector<std::vector<OrbDescriptor>> images(static_cast<size_t>(n));
  for (int i = 0; i < n; ++i) {
    images[static_cast<size_t>(i)].assign(data.members.begin(),
                                          data.members.begin() + (i + 1) * members_per_centre);
  }
  return images;
}

TEST(BinaryVocabularyConfigTest, ValidatesEveryField) {
  EXPECT_EQ(BinaryVocabularyConfig{}.validate(), "");
  BinaryVocabularyConfig c;
  c.branching = 1;
  EXPECT_NE(c.validate().find("branching"), std::string::npos);
  c = {};
  c.levels = 0;
  EXPECT_NE(c.validate().find("levels"), std::string::npos);
  c = {};
  c.branching = 64;
  c.levels = 6;  // 2^36 nodes
  EXPECT_NE(c.validate().find("2^31"), std::string::npos);
  c = {};
  c.max_iterations = 0;
  EXPECT_NE(c.validate().find("max_iterations"), std::string::npos);
  EXPECT_THROW(BinaryVocabulary::train({{OrbDescriptor{}}}, c), std::invalid_argument);
  EXPECT_THROW(BinaryVocabulary::train({{}, {}}, BinaryVocabularyConfig{}), std::invalid_argument);
}

TEST(BinaryVocabularyTest, OneLevelVocabularyOfClusteredDataHasTheCentresAsWordsWithIdf) {
  const test::ClusteredData data = makeClusteredData(10, 20, 10, 11);
  BinaryVocabularyConfig config;
  config.branching = 10;
  config.levels = 1;
  BinaryVocabularyTrainingStats stats;
  const BinaryVocabulary v =
      BinaryVocabulary::train(nestedImages(data, 10, 20), config, "clusters", &stats);
  ASSERT_EQ(v.wordCount(), 10u);
  EXPECT_EQ(v.nodeCount(), 11u);
  EXPECT_EQ(stats.images, 10u);
  EXPECT_EQ(stats.descriptors, 20u * 55u);
  EXPECT_EQ(v.description(), "clusters");
  for (size_t c = 0; c < 10; ++c) {
    const WordId w = v.wordOf(data.centres[c]);
    EXPECT_EQ(v.wordDescriptor(w), data.centres[c]);
    EXPECT_EQ(v.nodeDepth(v.wordNode(w)), 1);
    // Centre c is in images c..9: idf = log(10 / (10 - c)); centre 0 is in every image.
    EXPECT_NEAR(v.wordWeight(w), std::log(10.0 / (10.0 - static_cast<double>(c))), 1e-12);
  }
  for (size_t i = 0; i < data.members.size(); ++i) {
    EXPECT_EQ(v.wordDescriptor(v.wordOf(data.members[i])),
              data.centres[static_cast<size_t>(data.centre_of[i])]);
  }
}

TEST(BinaryVocabularyTest, TwoLevelTreeRecoversSubClustersAsWords) {
  // 4 groups of 4 sub-centres 40 bits from their group centre; members 6 bits from a sub-centre.
  std::mt19937_64 rng(9);
  std::vector<OrbDescriptor> subs, members;
  std::vector<size_t> sub_of;
  for (int g = 0; g < 4; ++g) {
    const OrbDescriptor top = test::randomDescriptor(rng);
    for (int s = 0; s < 4; ++s) {
      subs.push_back(test::flipBits(top, 40, rng));
      for (int m = 0; m < 25; ++m) {
        members.push_back(test::flipBits(subs.back(), 6, rng));
        sub_of.push_back(subs.size() - 1);
      }
    }
  }
  BinaryVocabularyConfig config;
  config.branching = 4;
  config.levels = 2;
  const BinaryVocabulary v = BinaryVocabulary::train({members}, config);
  ASSERT_EQ(v.wordCount(), 16u);
  EXPECT_EQ(v.nodeCount(), 21u);
  std::set<WordId> words;
  for (size_t i = 0; i < members.size(); ++i) {
    const WordId w = v.wordOf(members[i]);
    EXPECT_EQ(v.wordDescriptor(w), subs[sub_of[i]]) << "member " << i;
    EXPECT_EQ(v.nodeDepth(v.wordNode(w)), 2);
    words.insert(w);
  }
  EXPECT_EQ(words.size(), 16u);
  // One image: every word is in all images, idf 0, so the BoW vector is empty.
  EXPECT_TRUE(v.transform(members).empty());
}

TEST(BinaryVocabularyTest, TrainingIsDeterministicAndIndependentOfTheThreadCount) {
  std::mt19937_64 rng(21);
  std::vector<std::vector<OrbDescriptor>> images(5);
  for (auto& image : images) {
    for (int i = 0; i < 300; ++i) image.push_back(test::randomDescriptor(rng));
  }
  BinaryVocabularyConfig config;
  config.branching = 6;
  config.levels = 4;
  const std::string one = BinaryVocabulary::train(images, config).serialize();
  EXPECT_EQ(BinaryVocabulary::train(images, config).serialize(), one);
  config.num_threads = 3;
  BinaryVocabularyTrainingStats stats;
  EXPECT_EQ(BinaryVocabulary::train(images, config, "", &stats).serialize(), one);
  EXPECT_EQ(stats.descriptors, 1500u);
  EXPECT_GT(stats.words, 500u);  // random data splits down to small leaves
  config.seed = 2;
  EXPECT_NE(BinaryVocabulary::train(images, config).serialize(), one);
}

class TransformTest : public ::testing::Test {
 protected:
  TransformTest() : data_(makeClusteredData(40, 10, 12, 5)), v_(train()) {}

  BinaryVocabulary train() const {
    // 8 images, image i has the members of centres 5i .. 5i+4 (each word in one image).
    std::vector<std::vector<OrbDescriptor>> images(8);
    for (size_t i = 0; i < data_.members.size(); ++i) {
      images[static_cast<size_t>(data_.centre_of[i]) / 5].push_back(data_.members[i]);
    }
    images_ = images;
    BinaryVocabularyConfig config;
    config.branching = 4;
    config.levels = 3;
    return BinaryVocabulary::train(images, config);
  }

  test::ClusteredData data_;
  mutable std::vector<std::vector<OrbDescriptor>> images_;
  BinaryVocabulary v_;
};

TEST_F(TransformTest, BowVectorIsSortedNormalisedAndScoresOneAgainstItself) {
  ASSERT_EQ(images_.size(), 8u);
  for (const auto& image : images_) {
    const BowVector bow = v_.transform(image);
    ASSERT_FALSE(bow.empty());
    double sum = 0.0;
    for (size_t i = 0; i < bow.size(); ++i) {
      EXPECT_GT(bow[i].second, 0.0);
      if (i > 0) {
        EXPECT_LT(bow[i - 1].first, bow[i].first);
      }
      sum += bow[i].second;
    }
    EXPECT_NEAR(sum, 1.0, 1e-12);
    EXPECT_NEAR(BinaryVocabulary::score(bow, bow), 1.0, 1e-12);
  }
  // Images without common words score 0; half of an image scores between.
  const BowVector a = v_.transform(images_[0]), b = v_.transform(images_[1]);
  EXPECT_EQ(BinaryVocabulary::score(a, b), 0.0);
  const std::vector<OrbDescriptor> half(images_[0].begin(), images_[0].begin() + 25);
  const double partial = BinaryVocabulary::score(a, v_.transform(half));
  EXPECT_GT(partial, 0.3);
  EXPECT_LT(partial, 0.9);
  EXPECT_TRUE(v_.transform(std::vector<OrbDescriptor>{}).empty());
}

TEST_F(TransformTest, AnyNumberOfFeaturesGivesEachItsOwnWord) {
  // transform() descends 16 descriptors at a time: counts around that batch size give the
  // idf-weighted histogram of the words wordOf() finds one by one, normalised.
  std::vector<OrbDescriptor> all;
  for (const auto& image : images_) all.insert(all.end(), image.begin(), image.end());
  ASSERT_GT(all.size(), 100u);
  for (const size_t n : {size_t{1}, size_t{15}, size_t{16}, size_t{17}, size_t{33}, all.size()}) {
    const std::vector<OrbDescriptor> features(all.begin(), all.begin() + static_cast<long>(n));
    std::map<WordId, double> expected;
    double total = 0.0;
    for (const OrbDescriptor& d : features) {
      const WordId w = v_.wordOf(d);
      expected[w] += v_.wordWeight(w);
      total += v_.wordWeight(w);
    }
    const BowVector bow = v_.transform(features);
    ASSERT_EQ(bow.size(), expected.size()) << n << " features";
    size_t i = 0;
    for (const auto& [word, weight] : expected) {
      EXPECT_EQ(bow[i].first, word) << n << " features";
      EXPECT_NEAR(bow[i].second, weight / total, 1e-12) << n << " features";
      ++i;
    }
  }
}

TEST_F(TransformTest, ScoreIsDbow2sL1Formula) {
  const BowVector a{{1, 0.5}, {3, 0.25}, {7, 0.25}}, b{{1, 0.25}, {2, 0.25}, {7, 0.5}};
  // 1 - 0.5 (|0.5 - 0.25| + 0.25 + 0.25 + |0.25 - 0.5|) = 0.5
  EXPECT_NEAR(BinaryVocabulary::score(a, b), 0.5, 1e-15);
  EXPECT_NEAR(BinaryVocabulary::score(b, a), 0.5, 1e-15);
  EXPECT_EQ(sharedWordCount(a, b), 2);
  EXPECT_EQ(BinaryVocabulary::score(a, {}), 0.0);
}

TEST_F(TransformTest, FeatureVectorIndexesEveryFeatureOnceUnderItsAncestor) {
  const std::vector<OrbDescriptor>& image = images_[3];
  for (const int levels_up : {0, 1, 2, 3, 7}) {
    FeatureVector fv;
    BowVector bow;
    v_.transform(image, &bow, &fv, levels_up);
    EXPECT_EQ(bow, v_.transform(image));
    std::vector<int> seen(image.size(), 0);
    int nodes_at_depth_two = 0;
    for (size_t n = 0; n < fv.size(); ++n) {
      if (n > 0) {
        EXPECT_LT(fv[n - 1].first, fv[n].first);
      }
      const int depth = v_.nodeDepth(fv[n].first);
      nodes_at_depth_two += depth == 2;
      for (const uint32_t i : fv[n].second) {
        ++seen[i];
        // The ancestor of the feature's leaf at depth 3 - levels_up (or the leaf if shallower).
        NodeId expected = v_.wordNode(v_.wordOf(image[i]));
        while (v_.nodeDepth(expected) > std::max(0, 3 - levels_up)) {
          expected = v_.nodeParent(expected);
        }
        EXPECT_EQ(fv[n].first, expected);
        EXPECT_EQ(depth, v_.nodeDepth(expected));
        if (levels_up >= 3) {
          EXPECT_EQ(fv[n].first, 0u);
        }
      }
    }
    for (const int s : seen) EXPECT_EQ(s, 1);
    if (levels_up == 1) {
      EXPECT_GT(nodes_at_depth_two, 1);
    }
  }
}

}  // namespace
}  // namespace cblox
