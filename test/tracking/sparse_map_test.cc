// The sparse map's bookkeeping: feature grid queries, observations in both directions,
// covisibility weights and the spanning tree, keyframe culling with re-parenting, landmark
// retirement and replacement, landmark descriptor / viewing range / scale prediction.

#include "core/tracking/sparse_map.h"

#include <algorithm>
#include <map>
#include <memory>
#include <optional>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "core/features/scale_pyramid.h"
#include "core/tracking/feature_grid.h"
#include "core/tracking/solved_poses.h"

namespace cblox {
namespace {

// Features at (10 i, 10 i) with depth 2 m (stereo) for even i, none for odd i.
std::shared_ptr<FrameFeatures> makeFeatures(size_t n) {
  auto f = std::make_shared<FrameFeatures>();
  for (size_t i = 0; i < n; ++i) {
    Keypoint k;
    k.u = static_cast<float>(10 * (i % 60));
    k.v = static_cast<float>(10 * (i / 60));
    k.octave = static_cast<int>(i % 3);
    f->keypoints.push_back(k);
    OrbDescriptor d;
    d.words[0] = i;
    f->descriptors.push_back(d);
    f->depth.push_back(i % 2 == 0 ? 2.0f : -1.0f);
    f->right_u.push_back(i % 2 == 0 ? k.u - 20.0f : -1.0f);
  }
  f->grid = FeatureGrid(f->keypoints, 640, 480);
  return f;
}

Transformationd camera(double x) {
  return Transformationd(Eigen::Quaterniond::Identity(), Eigen::Vector3d(-x, 0, 0));  // T_C_G
}

TEST(FeatureGridTest, FindsExactlyTheFeaturesInTheSquareAndOctaveRange) {
  std::vector<Keypoint> keypoints;
  for (int v = 0; v < 480; v += 7) {
    for (int u = 0; u < 640; u += 7) {
      Keypoint k;
      k.u = static_cast<float>(u) + 0.5f;
      k.v = static_cast<float>(v) + 0.25f;
      k.octave = (u / 7) % 4;
      keypoints.push_back(k);
    }
  }
  const FeatureGrid grid(keypoints, 640, 480);
  for (const auto& [u, v, r, lo, hi] :
       std::vector<std::tuple<float, float, float, int, int>>{{100.0f, 100.0f, 15.0f, 0, -1},
                                                              {3.0f, 477.0f, 30.0f, 1, 2},
                                                              {639.0f, 0.0f, 100.0f, 3, 3}}) {
    std::vector<uint32_t> expected;
    for (uint32_t i = 0; i < keypoints.size(); ++i) {
      const Keypoint& k = keypoints[i];
      if (std::abs(k.u - u) <= r && std::abs(k.v - v) <= r && k.octave >= lo &&
          (hi < 0 || k.octave <= hi)) {
        expected.push_back(i);
      }
    }
    ASSERT_FALSE(expected.empty());
    EXPECT_EQ(grid.featuresInArea(keypoints, u, v, r, lo, hi), expected);
  }
  EXPECT_TRUE(grid.featuresInArea(keypoints, -500.0f, -500.0f, 10.0f).empty());
}

struct SmallMap {
  SparseMap map;
  std::vector<Keyframe*> keyframes;
  std::vector<Landmark*> landmarks;
};

// Keyframe k observes landmarks [20 k, 20 k + 40): neighbours share 20, others none.
void buildChain(SmallMap* m, int num_keyframes) {
  const int num_landmarks = 20 * num_keyframes + 20;
  for (int k = 0; k < num_keyframes; ++k) {
    m->keyframes.push_back(m->map.addKeyframe(static_cast<uint64_t>(10 * k), 1000 * k,
                                              makeFeatures(200), camera(0.1 * k)));
  }
  for (int l = 0; l < num_landmarks; ++l) {
    m->landmarks.push_back(
        m->map
            .addLandmark(Eigen::Vector3d(0.01 * l, 0, 3),
                         m->keyframes[static_cast<size_t>(std::min(l / 20, num_keyframes - 1))])
            .get());
  }
  for (int k = 0; k < num_keyframes; ++k) {
    for (int l = 20 * k; l < 20 * k + 40; ++l) {
      SparseMap::addObservation(m->keyframes[static_cast<size_t>(k)],
                                static_cast<uint32_t>(l - 20 * k + 100),
                                m->landmarks[static_cast<size_t>(l)]);
    }
  }
  for (Keyframe* k : m->keyframes) k->updateConnections();
}

TEST(SparseMapTest, ObservationsAreKeptInBothDirections) {
  SmallMap m;
  buildChain(&m, 3);
  Landmark* l = m.landmarks[25];  // seen by keyframes 0 (feature 125) and 1 (feature 105)
  ASSERT_EQ(l->observations().size(), 2u);
  EXPECT_EQ(l->indexIn(m.keyframes[0]), 125);
  EXPECT_EQ(l->indexIn(m.keyframes[1]), 105);
  EXPECT_EQ(l->indexIn(m.keyframes[2]), -1);
  EXPECT_EQ(m.keyframes[0]->landmark(125), l);
  // Feature 125 has no depth (odd), 105 neither: two mono observations.
  EXPECT_EQ(l->numObservations(), 2);
  Landmark* s = m.landmarks[24];  // features 124 and 104: stereo
  EXPECT_EQ(s->numObservations(), 4);
  SparseMap::eraseObservation(m.keyframes[0], 124);
  EXPECT_EQ(m.keyframes[0]->landmark(124), nullptr);
  EXPECT_EQ(s->numObservations(), 2);
  EXPECT_EQ(s->indexIn(m.keyframes[0]), -1);
  EXPECT_EQ(m.keyframes[0]->numTrackedLandmarks(), 39);
}

TEST(SparseMapTest, CovisibilityWeightsCountSharedLandmarks) {
  SmallMap m;
  buildChain(&m, 4);
  // Neighbours share exactly 20 landmarks (>= 15: an edge); others share none.
  EXPECT_EQ(m.keyframes[1]->weight(m.keyframes[0]), 20);
  EXPECT_EQ(m.keyframes[1]->weight(m.keyframes[2]), 20);
  EXPECT_EQ(m.keyframes[1]->weight(m.keyframes[3]), 0);
  EXPECT_EQ(m.keyframes[0]->weight(m.keyframes[1]), 20);
  EXPECT_EQ(m.keyframes[1]->covisibleByWeight(),
            (std::vector<Keyframe*>{m.keyframes[0], m.keyframes[2]}));  // ties by id
  EXPECT_EQ(m.keyframes[1]->bestCovisible(1), (std::vector<Keyframe*>{m.keyframes[0]}));
  EXPECT_TRUE(m.keyframes[1]->covisibleWithWeightAtLeast(21).empty());
  // Spanning tree: each keyframe's parent is its best neighbour at its first update.
  EXPECT_EQ(m.keyframes[0]->parent(), nullptr);
  EXPECT_EQ(m.keyframes[1]->parent(), m.keyframes[0]);
  EXPECT_EQ(m.keyframes[2]->parent(), m.keyframes[1]);
  EXPECT_EQ(m.keyframes[3]->parent(), m.keyframes[2]);
  EXPECT_EQ(m.keyframes[1]->children().count(m.keyframes[2]), 1u);
  // A weaker link: 5 shared landmarks give no edge while a strong one exists.
  for (uint32_t i = 0; i < 5; ++i) {
    SparseMap::addObservation(m.keyframes[3], i, m.landmarks[i]);
  }
  m.keyframes[3]->updateConnections();
  EXPECT_EQ(m.keyframes[3]->weight(m.keyframes[0]), 0);
  EXPECT_EQ(m.keyframes[0]->weight(m.keyframes[3]), 0);
}

TEST(SparseMapTest, NeighbourOrderFollowsEveryEdgeChangeInPlace) {
  // addConnection / eraseConnection keep the order in place: after any sequence of edge
  // changes it is the full order, decreasing weight and ties by increasing id.
  SmallMap m;
  buildChain(&m, 12);
  Keyframe* k = m.keyframes[5];
  std::mt19937 rng(4);
  std::uniform_int_distribution<int> pick(0, 11), weight(15, 19), erase(0, 3);
  for (int step = 0; step < 400; ++step) {
    Keyframe* other = m.keyframes[static_cast<size_t>(pick(rng))];
    if (other == k) continue;
    if (erase(rng) == 0) {
      k->eraseConnection(other);
    } else {
      k->addConnection(other, weight(rng));  // few weights: many ties and unchanged edges
    }
    std::vector<std::pair<int, KeyframeId>> expected;
    for (const auto& [o, w] : k->connections()) expected.emplace_back(-w, o->id);
    std::sort(expected.begin(), expected.end());
    const std::vector<Keyframe*>& order = k->covisibleByWeight();
    ASSERT_EQ(order.size(), expected.size()) << "step " << step;
    for (size_t i = 0; i < order.size(); ++i) {
      ASSERT_EQ(order[i]->id, expected[i].second) << "step " << step << " position " << i;
      ASSERT_EQ(k->weight(order[i]), -expected[i].first);
    }
    const std::vector<Keyframe*> heavy = k->covisibleWithWeightAtLeast(18);
    for (size_t i = 0; i < order.size(); ++i) {
      ASSERT_EQ(i < heavy.size(), k->weight(order[i]) >= 18);
    }
  }
}

TEST(SparseMapTest, CullingAKeyframeReparentsItsChildrenAndRetiresOrphans) {
  SmallMap m;
  buildChain(&m, 4);
  // Make keyframe 3 also share 30 landmarks with keyframe 1, so when 2 goes, 3 hangs on 1.
  for (uint32_t i = 0; i < 30; ++i) {
    SparseMap::addObservation(m.keyframes[3], 10 + i, m.landmarks[20 + i]);
  }
  m.keyframes[3]->updateConnections();
  EXPECT_EQ(m.keyframes[3]->parent(), m.keyframes[2]);  // unchanged after the first update
  // Before culling: the landmarks keyframe 2 observes, with what they keep without it.
  std::vector<std::pair<LandmarkId, int>> kept_observations;
  for (Landmark* l : m.keyframes[2]->landmarks()) {
    if (l == nullptr) continue;
    const int index = l->indexIn(m.keyframes[2]);
    const int own = m.keyframes[2]->features().hasDepth(static_cast<size_t>(index)) ? 2 : 1;
    kept_observations.emplace_back(l->id, l->numObservations() - own);
  }
  ASSERT_EQ(kept_observations.size(), 40u);
  const size_t landmarks_before = m.map.numLandmarks();
  m.map.cullKeyframe(m.keyframes[2]);
  EXPECT_TRUE(m.keyframes[2]->bad());
  EXPECT_EQ(m.map.numKeyframes(), 3u);
  EXPECT_EQ(m.map.keyframes(),
            (std::vector<Keyframe*>{m.keyframes[0], m.keyframes[1], m.keyframes[3]}));
  EXPECT_EQ(m.keyframes[3]->parent(), m.keyframes[1]);
  EXPECT_EQ(m.keyframes[1]->children().count(m.keyframes[3]), 1u);
  EXPECT_EQ(m.keyframes[1]->children().count(m.keyframes[2]), 0u);
  EXPECT_EQ(m.keyframes[1]->weight(m.keyframes[2]), 0);
  // T_parent_this keeps keyframe 2's pose relative to its former parent (x 0.1 -> 0.2).
  EXPECT_TRUE(m.keyframes[2]->T_parent_this().translation().isApprox(Eigen::Vector3d(0.1, 0, 0)));
  // ORB-SLAM2's rule: a landmark left with <= 2 observations (stereo counting 2) is retired
  // and forgotten by its keyframes; the others stay.
  size_t retired = 0;
  for (const auto& [id, kept] : kept_observations) {
    const std::shared_ptr<Landmark> l = m.map.landmark(id);
    if (kept <= 2) {
      EXPECT_EQ(l, nullptr) << id;
      ++retired;
    } else {
      ASSERT_NE(l, nullptr) << id;
      EXPECT_EQ(l->numObservations(), kept) << id;
    }
  }
  EXPECT_EQ(m.map.numLandmarks(), landmarks_before - retired);
  EXPECT_EQ(m.map.landmark(65), nullptr);  // kf 2 and 3 only
  EXPECT_EQ(m.keyframes[3]->landmark(105), nullptr);
  EXPECT_NE(m.map.landmark(44), nullptr);  // stereo in kf 1 and 3: 4 observations left
  EXPECT_GT(retired, 20u);
  // The first keyframe is never culled.
  m.map.cullKeyframe(m.keyframes[0]);
  EXPECT_FALSE(m.keyframes[0]->bad());
}

// Culled keyframes stay on their ancestors: in a chain 0-1-2-3-4 (parents by id), cull 3,
// then 2, so 3's chain is 3 -> 2 -> 1. Moving keyframe 1 by a known transform moves 2 and 3
// with it, exactly as T_G_1 * T_1_k; keyframes whose ancestor did not move stay.
TEST(SparseMapTest, CulledKeyframesFollowTheirGoodAncestorInPoseBatches) {
  SmallMap m;
  buildChain(&m, 5);
  // Rotated poses so the products are not plain sums of x offsets.
  for (int k = 0; k < 5; ++k) {
    const Eigen::Quaterniond q(
        Eigen::AngleAxisd(0.1 * k, Eigen::Vector3d(0.2, 1, 0.3).normalized()));
    m.keyframes[k]->setPose(Transformationd(q, Eigen::Vector3d(0.3 * k, -0.1 * k, 0.05 * k)));
  }
  const Transformationd T_G_2 = m.keyframes[2]->T_G_C(), T_G_3 = m.keyframes[3]->T_G_C();
  const Transformationd T_G_1 = m.keyframes[1]->T_G_C();
  m.map.cullKeyframe(m.keyframes[3]);
  ASSERT_TRUE(m.keyframes[3]->bad());
  m.map.cullKeyframe(m.keyframes[2]);
  ASSERT_TRUE(m.keyframes[2]->bad());
  // 3 keeps its parent 2 (a chain of two culled keyframes); 4 went to 2, then to 1.
  ASSERT_EQ(m.keyframes[3]->parent(), m.keyframes[2]);
  ASSERT_EQ(m.keyframes[2]->parent(), m.keyframes[1]);
  EXPECT_EQ(m.keyframes[4]->parent(), m.keyframes[1]);

  for (const int k : {2, 3}) {
    const std::optional<KeyframeAncestor> a = SparseMap::goodAncestor(m.keyframes[k]);
    ASSERT_TRUE(a.has_value());
    EXPECT_EQ(a->ancestor, m.keyframes[1]);
    EXPECT_TRUE((T_G_1 * a->T_A_K).isApprox(k == 2 ? T_G_2 : T_G_3, 1e-12));
  }
  // A stop predicate ends the walk early, at a culled keyframe (2 for 3) or at the start.
  const auto stopAt2 = [](const Keyframe& k) { return k.id == 2; };
  const std::optional<KeyframeAncestor> at2 = SparseMap::goodAncestor(m.keyframes[3], stopAt2);
  ASSERT_TRUE(at2.has_value());
  EXPECT_EQ(at2->ancestor, m.keyframes[2]);
  EXPECT_TRUE((T_G_2 * at2->T_A_K).isApprox(T_G_3, 1e-12));
  const std::optional<KeyframeAncestor> start = SparseMap::goodAncestor(m.keyframes[2], stopAt2);
  ASSERT_TRUE(start.has_value());
  EXPECT_EQ(start->ancestor, m.keyframes[2]);
  EXPECT_TRUE(start->T_A_K.isApprox(Transformationd(), 0.0));
  const std::optional<KeyframeAncestor> self = SparseMap::goodAncestor(m.keyframes[4]);
  ASSERT_TRUE(self.has_value());
  EXPECT_EQ(self->ancestor, m.keyframes[4]);
  EXPECT_TRUE(self->T_A_K.isApprox(Transformationd(), 0.0));

  // Keyframe 1 moves (as a local BA would set it): 2 and 3 follow, 0 and 4 are not added.
  const Transformationd move =
      Transformationd::exp((Transformationd::Vec6() << 0.5, -0.2, 0.1, 0.05, 0.2, -0.1).finished());
  const Transformationd T_G_1_new = move * T_G_1;
  m.keyframes[1]->setPose(T_G_1_new.inverse());
  KeyframePoseBatch batch{{1, T_G_1_new}};
  m.map.moveCulledKeyframes(&batch);
  ASSERT_EQ(batch.size(), 3u);
  std::map<KeyframeId, Transformationd> got(batch.begin(), batch.end());
  ASSERT_EQ(got.count(2), 1u);
  ASSERT_EQ(got.count(3), 1u);
  EXPECT_TRUE(got.at(2).isApprox(T_G_1_new * T_G_1.inverse() * T_G_2, 1e-12));
  EXPECT_TRUE(got.at(3).isApprox(T_G_1_new * T_G_1.inverse() * T_G_3, 1e-12));
  // Stored as well, so the culled keyframes' poses are current everywhere (checkpoints).
  EXPECT_TRUE(m.keyframes[2]->T_G_C().isApprox(got.at(2), 1e-12));
  EXPECT_TRUE(m.keyframes[3]->T_G_C().isApprox(got.at(3), 1e-12));

  // A batch that moves only keyframe 4 moves no culled keyframe.
  KeyframePoseBatch other{{4, m.keyframes[4]->T_G_C()}};
  m.map.moveCulledKeyframes(&other);
  EXPECT_EQ(other.size(), 1u);
}

// A solution read from the map, solved without its lock and applied after (the loop
// closer's essential graph): keyframes get the solved poses, a keyframe a local BA moved
// meanwhile keeps that change on top, keyframes made meanwhile follow their parent (a chain
// of two), and landmarks keep their place in the frame of the keyframe that placed them, or
// of the one they were moved with.
TEST(SparseMapTest, SolvedPosesApplyToTheMapAsItIsNow) {
  SmallMap m;
  buildChain(&m, 4);
  for (int k = 0; k < 4; ++k) {
    const Eigen::Quaterniond q(
        Eigen::AngleAxisd(0.1 * k, Eigen::Vector3d(0.2, 1, 0.3).normalized()));
    m.keyframes[k]->setPose(Transformationd(q, Eigen::Vector3d(0.3 * k, -0.1 * k, 0.05 * k)));
  }
  std::vector<Transformationd> read;
  for (const Keyframe* k : m.keyframes) read.push_back(k->T_C_G());
  const auto exp6 = [](double a, double b, double c, double d, double e, double f) {
    return Transformationd::exp((Transformationd::Vec6() << a, b, c, d, e, f).finished());
  };
  // The solution moves the world rigidly (G' = W G), and keyframe 2 by E besides.
  const Transformationd W = exp6(1.0, 2.0, -0.5, 0.1, -0.2, 0.3);
  const Transformationd E = exp6(0.3, 0.0, 0.1, 0.0, 0.05, 0.0);
  std::vector<Transformationd> solved;
  for (int k = 0; k < 4; ++k)
    solved.push_back((k == 2 ? E : Transformationd()) * read[k] * W.inverse());

  // Meanwhile: a local BA moves keyframe 2 by D; keyframe 4 is made next to 3 (parent 3) with
  // landmarks 100-119 of its own, keyframe 5 sees only those (parent 4).
  const Transformationd D = exp6(0.05, -0.02, 0.01, 0.02, 0.0, -0.01);
  m.keyframes[2]->setPose(D * read[2]);
  Keyframe* k4 = m.map.addKeyframe(40, 4000, makeFeatures(200), exp6(0.4, 0, 0.1, 0, 0.2, 0));
  Keyframe* k5 = m.map.addKeyframe(50, 5000, makeFeatures(200), exp6(0.5, 0, 0.2, 0, 0.3, 0));
  for (int l = 80; l < 100; ++l) {
    SparseMap::addObservation(k4, static_cast<uint32_t>(l - 80 + 100), m.landmarks[l]);
  }
  for (int l = 100; l < 120; ++l) {
    m.landmarks.push_back(m.map.addLandmark(Eigen::Vector3d(0.02 * l, 0.5, 4), k4).get());
    SparseMap::addObservation(k4, static_cast<uint32_t>(l - 100 + 120), m.landmarks[l]);
    SparseMap::addObservation(k5, static_cast<uint32_t>(l - 100 + 100), m.landmarks[l]);
  }
  k4->updateConnections();
  k5->updateConnections();
  ASSERT_EQ(k4->parent(), m.keyframes[3]);
  ASSERT_EQ(k5->parent(), k4);
  const Transformationd T_C4 = k4->T_C_G(), T_C5 = k5->T_C_G();
  std::vector<Eigen::Vector3d> p_before;
  for (const Landmark* l : m.landmarks) p_before.push_back(l->position());
  // Landmark 5 (placed by keyframe 0) was moved with keyframe 2 when the problem was read.
  const std::map<LandmarkId, const Keyframe*> anchor_of{{m.landmarks[5]->id, m.keyframes[2]}};

  const ScalePyramid pyramid(8, 1.2);
  applySolvedPoses(&m.map, m.keyframes, read, solved, anchor_of, pyramid);

  for (int k : {0, 1, 3}) EXPECT_TRUE(m.keyframes[k]->T_C_G().isApprox(solved[k], 1e-12)) << k;
  EXPECT_TRUE(m.keyframes[2]->T_C_G().isApprox(D * solved[2], 1e-12));
  EXPECT_TRUE(k4->T_C_G().isApprox(T_C4 * W.inverse(), 1e-12));  // its parent moved by W
  EXPECT_TRUE(k5->T_C_G().isApprox(T_C5 * W.inverse(), 1e-12));  // so did its parent's
  // Keyframe 2 went from D read[2] to D E read[2] W^-1: its landmarks (40-59, and 5) by
  // T_G_C2_new T_C2_G_before = W read[2]^-1 E^-1 read[2]; all others by W.
  const Transformationd by2 = W * read[2].inverse() * E.inverse() * read[2];
  for (size_t l = 0; l < m.landmarks.size(); ++l) {
    const bool with2 = (l >= 40 && l < 60) || l == 5;
    const Eigen::Vector3d expected = (with2 ? by2 : W) * p_before[l];
    EXPECT_LT((m.landmarks[l]->position() - expected).norm(), 1e-9) << "landmark " << l;
  }
  EXPECT_THROW(
      applySolvedPoses(&m.map, m.keyframes, read, std::span(solved).first(3), anchor_of, pyramid),
      std::invalid_argument);
}

TEST(SparseMapTest, ReplacingALandmarkMovesItsObservations) {
  SmallMap m;
  buildChain(&m, 3);
  Landmark* a = m.landmarks[5];   // keyframe 0 only (feature 105)
  Landmark* b = m.landmarks[45];  // keyframes 1 (feature 125) and 2 (feature 105)
  const std::shared_ptr<Landmark> keep_a = m.map.landmark(a->id);
  a->increaseVisible(4);
  a->increaseFound(2);
  m.map.replaceLandmark(a, b);
  EXPECT_TRUE(a->bad());
  EXPECT_EQ(a->replacement().get(), b);
  EXPECT_EQ(m.map.landmark(a->id), nullptr);
  EXPECT_EQ(m.keyframes[0]->landmark(105), b);
  EXPECT_EQ(b->indexIn(m.keyframes[0]), 105);
  EXPECT_EQ(b->observations().size(), 3u);
  EXPECT_EQ(b->visible(), 1 + 5);
  EXPECT_EQ(b->found(), 1 + 3);
}

TEST(SparseMapTest, RetiredLandmarkStaysAliveForFramesThatHoldIt) {
  SmallMap m;
  buildChain(&m, 2);
  std::shared_ptr<Landmark> held = m.map.landmark(30);
  m.map.retireLandmark(held.get());
  EXPECT_TRUE(held->bad());
  EXPECT_TRUE(held->observations().empty());
  EXPECT_EQ(m.keyframes[0]->landmark(130), nullptr);
  EXPECT_EQ(m.keyframes[1]->landmark(110), nullptr);
  EXPECT_EQ(m.map.landmark(30), nullptr);
}

TEST(LandmarkTest, DescriptorNormalRangeAndScale) {
  SmallMap m;
  buildChain(&m, 2);
  const ScalePyramid pyramid(8, 1.2);
  Landmark* l = m.landmarks[25];  // keyframes 0 (x = 0) and 1 (x = 0.1), point (0.25, 0, 3)
  l->updateDescriptor();
  // Two descriptors: words[0] = 125 or 105; median of {0, d} = 0 for both: the first wins.
  EXPECT_EQ(l->descriptor().words[0], 125u);
  l->updateNormalAndDepth(pyramid);
  const Eigen::Vector3d p(0.25, 0, 3);
  const Eigen::Vector3d n0 = p.normalized(), n1 = (p - Eigen::Vector3d(0.1, 0, 0)).normalized();
  EXPECT_TRUE(l->normal().isApprox((n0 + n1) / 2, 1e-12));
  // Reference keyframe 1 (the landmark was made there), feature 105: octave 0, so the
  // largest detection distance is the distance itself and the smallest is 1.2^7 closer.
  const double dmax = (p - Eigen::Vector3d(0.1, 0, 0)).norm() * pyramid.scale(0);
  EXPECT_EQ(l->referenceKeyframe(), m.keyframes[1]);
  EXPECT_NEAR(l->maxDistance(), 1.2 * dmax, 1e-9);
  EXPECT_NEAR(l->minDistance(), 0.8 * dmax / pyramid.scale(7), 1e-6);
  // Level = ceil(log(dmax / distance) / log 1.2).
  EXPECT_EQ(l->predictScale(dmax, pyramid), 0);
  EXPECT_EQ(l->predictScale(dmax / 1.1, pyramid), 1);
  EXPECT_EQ(l->predictScale(dmax / 1.3, pyramid), 2);
  EXPECT_EQ(l->predictScale(dmax / 1e6, pyramid), 7);
}

}  // namespace
}  // namespace cblox
