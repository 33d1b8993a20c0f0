#include "core/vocabulary/keyframe_database.h"

#include <atomic>
#include <random>
#include <thread>

#include <gtest/gtest.h>

namespace cblox {
namespace {

/// A BoW vector over the given words with the given weights (already summing to 1).
BowVector bow(const std::vector<std::pair<WordId, double>>& entries) { return entries; }

BowVector uniform(WordId first, WordId last, double weight) {
  BowVector v;
  for (WordId w = first; w <= last; ++w) v.emplace_back(w, weight);
  return v;
}

BowVector concat(BowVector a, const BowVector& b) {
  a.insert(a.end(), b.begin(), b.end());
  return a;
}

/// Query: words 0..9 at 0.1. Keyframes (shared words with the query, L1 score):
///   1: word 0 at 0.55, words 1..9 at 0.05        (10, 0.55)
///   2: words 0..7 at 0.1, word 18 at 0.2          ( 8, 0.80)
///   3: words 0..6 at 0.1, word 19 at 0.3          ( 7, 0.70)  below 0.8 x 10 shared words
///   4: words 2..9 at 0.05, word 17 at 0.6         ( 8, 0.40)
///   5: words 10..16                               ( 0, 0   )
class KeyframeDatabaseTest : public ::testing::Test {
 protected:
  KeyframeDatabaseTest() {
    db_.add(1, concat(bow({{0, 0.55}}), uniform(1, 9, 0.05)));
    db_.add(2, concat(uniform(0, 7, 0.1), bow({{18, 0.2}})));
    db_.add(3, concat(uniform(0, 6, 0.1), bow({{19, 0.3}})));
    db_.add(4, concat(uniform(2, 9, 0.05), bow({{17, 0.6}})));
    db_.add(5, uniform(10, 16, 1.0 / 7.0));
  }

  const BowVector query_ = uniform(0, 9, 0.1);
  KeyframeDatabase db_;
};

TEST_F(KeyframeDatabaseTest, RelocalizationScoresKeyframesSharingEnoughWords) {
  const std::vector<PlaceCandidate> c = db_.queryRelocalizationCandidates(query_, 0);
  ASSERT_EQ(c.size(), 3u);  // 3 shares too few words, 5 none
  EXPECT_EQ(c[0].id, 2);
  EXPECT_NEAR(c[0].score, 0.8, 1e-12);
  EXPECT_EQ(c[0].shared_words, 8);
  EXPECT_EQ(c[0].accumulated_score, c[0].score);
  EXPECT_EQ(c[1].id, 1);
  EXPECT_NEAR(c[1].score, 0.55, 1e-12);
  EXPECT_EQ(c[1].shared_words, 10);
  EXPECT_EQ(c[2].id, 4);
  EXPECT_NEAR(c[2].score, 0.4, 1e-12);
  EXPECT_EQ(db_.queryRelocalizationCandidates(query_, 2).size(), 2u);
  // An identical vector scores 1 and comes first.
  db_.add(6, query_);
  const std::vector<PlaceCandidate> with_copy = db_.queryRelocalizationCandidates(query_, 1);
  ASSERT_EQ(with_copy.size(), 1u);
  EXPECT_EQ(with_copy[0].id, 6);
  EXPECT_NEAR(with_copy[0].score, 1.0, 1e-12);
  EXPECT_TRUE(db_.queryRelocalizationCandidates({}, 0).empty());
}

TEST_F(KeyframeDatabaseTest, LoopQueryExcludesKeyframesAndAppliesTheMinimumScore) {
  // Without 2, keyframe 1 sets the word threshold (8 of 10); 4 scores below 0.5.
  const std::vector<PlaceCandidate> c = db_.queryLoopCandidates(query_, 0.5, {2, 42}, 0);
  ASSERT_EQ(c.size(), 1u);
  EXPECT_EQ(c[0].id, 1);
  EXPECT_EQ(db_.queryLoopCandidates(query_, 0.9, {}, 0).size(), 0u);
  EXPECT_EQ(db_.queryLoopCandidates(query_, 0.0, {}, 0).size(), 3u);
}

TEST_F(KeyframeDatabaseTest, NeighbourGroupsAccumulateScoresLikeOrbSlam2) {
  const KeyframeDatabase::NeighbourFunction neighbours = [](KeyframeId id) {
    if (id == 1) return std::vector<KeyframeId>{4, 3, 99};  // 3 unscored, 99 unknown
    if (id == 4) return std::vector<KeyframeId>{1};
    return std::vector<KeyframeId>{};
  };
  // Groups: {1, 4} -> 0.95 (best 1, twice, merged), {2} -> 0.8 >= 0.75 x 0.95.
  const std::vector<PlaceCandidate> c = db_.queryRelocalizationCandidates(query_, 0, neighbours);
  ASSERT_EQ(c.size(), 2u);
  EXPECT_EQ(c[0].id, 1);
  EXPECT_NEAR(c[0].accumulated_score, 0.95, 1e-12);
  EXPECT_NEAR(c[0].score, 0.55, 1e-12);
  EXPECT_EQ(c[1].id, 2);
  EXPECT_NEAR(c[1].accumulated_score, 0.8, 1e-12);
  // A stricter ratio keeps only the best group.
  KeyframeDatabaseConfig strict;
  strict.min_accumulated_score_ratio = 0.9;
  KeyframeDatabase db(strict);
  db.add(1, concat(bow({{0, 0.55}}), uniform(1, 9, 0.05)));
  db.add(2, concat(uniform(0, 7, 0.1), bow({{18, 0.2}})));
  db.add(4, concat(uniform(2, 9, 0.05), bow({{17, 0.6}})));
  const std::vector<PlaceCandidate> best = db.queryRelocalizationCandidates(query_, 0, neighbours);
  ASSERT_EQ(best.size(), 1u);
  EXPECT_EQ(best[0].id, 1);
}

TEST_F(KeyframeDatabaseTest, AddReplacesEraseRemovesAndConfigIsValidated) {
  EXPECT_EQ(db_.size(), 5u);
  EXPECT_TRUE(db_.contains(3));
  db_.add(2, uniform(30, 31, 0.5));  // replaced: no longer shares words with the query
  EXPECT_EQ(db_.size(), 5u);
  std::vector<PlaceCandidate> c = db_.queryRelocalizationCandidates(query_, 0);
  ASSERT_FALSE(c.empty());
  EXPECT_EQ(c[0].id, 1);
  for (const PlaceCandidate& p : c) EXPECT_NE(p.id, 2);
  EXPECT_TRUE(db_.erase(1));
  EXPECT_FALSE(db_.erase(1));
  EXPECT_FALSE(db_.contains(1));
  c = db_.queryRelocalizationCandidates(query_, 0);
  ASSERT_EQ(c.size(), 2u);  // now 4 (8 words) and 3 (7 >= 0.8 x 8) qualify
  EXPECT_EQ(c[0].id, 3);
  EXPECT_EQ(c[1].id, 4);
  db_.clear();
  EXPECT_EQ(db_.size(), 0u);
  EXPECT_TRUE(db_.queryRelocalizationCandidates(query_, 0).empty());

  KeyframeDatabaseConfig bad;
  bad.min_shared_words_ratio = 0.0;
  EXPECT_NE(bad.validate().find("min_shared_words_ratio"), std::string::npos);
  EXPECT_THROW(KeyframeDatabase{bad}, std::invalid_argument);
  bad = {};
  bad.min_accumulated_score_ratio = 1.5;
  EXPECT_NE(bad.validate().find("min_accumulated_score_ratio"), std::string::npos);
}

TEST(KeyframeDatabaseConcurrencyTest, QueriesRunWhileKeyframesAreAddedAndErased) {
  KeyframeDatabase db;
  const BowVector target = uniform(0, 19, 0.05);
  db.add(0, target);
  std::atomic<bool> stop{false};
  std::atomic<int> queries{0}, wrong{0};
  auto reader = [&] {
    while (!stop.load()) {
      // Keyframe 0 is never erased and matches exactly: it must always come first.
      const std::vector<PlaceCandidate> c = db.queryRelocalizationCandidates(target, 3);
      if (c.empty() || c[0].id != 0) wrong.fetch_add(1);
      const std::vector<PlaceCandidate> loop = db.queryLoopCandidates(target, 0.0, {0}, 3);
      for (const PlaceCandidate& p : loop) {
        if (p.id == 0) wrong.fetch_add(1);
      }
      queries.fetch_add(1);
    }
  };
  std::thread r1(reader), r2(reader);
  while (queries.load() == 0) std::this_thread::yield();  // readers are running
  std::mt19937 rng(1);
  for (KeyframeId id = 1; id <= 2000; ++id) {
    BowVector v;
    const WordId first = static_cast<WordId>(rng() % 30);
    for (WordId w = first; w < first + 10; ++w) v.emplace_back(w, 0.1);
    db.add(id, v);
    if (id % 3 == 0) db.erase(id - 2);
  }
  const int queries_while_writing = queries.load();
  while (queries.load() < queries_while_writing + 10) std::this_thread::yield();
  stop = true;
  r1.join();
  r2.join();
  EXPECT_GT(queries.load(), 0);
  EXPECT_EQ(wrong.load(), 0);
  EXPECT_EQ(db.size(), 1u + 2000u - 666u);
}

}  // namespace
}  // namespace cblox
