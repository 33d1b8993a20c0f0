// Place recognition on simulator frames with vocabularies trained on the training scene
// sim:yard (texture seed 2) and evaluated on the evaluation scenes sim:room and sim:hall
// (texture seed 1): a small vocabulary trained here, and the build-time vocabulary
// (CBLOX_DEFAULT_VOCABULARY) when it was built.

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <numbers>

#include <gtest/gtest.h>

#include "core/vocabulary/binary_vocabulary.h"
#include "core/vocabulary/keyframe_database.h"
#include "test/vocabulary/build_time_vocabulary.h"
#include "test/vocabulary/sim_views.h"

namespace cblox {
namespace {

using test::SimView;
using test::viewOverlap;

struct Views {
  /// Room orbit every 1.5 s; query i is 0.2 s (10 cm, 4 degrees) after keyframe i.
  std::vector<SimView> orbit_keyframes, orbit_queries;
  /// Hall loop flown twice: lap 1 every 2 s, lap 2 every 2 s at a 1 s phase.
  std::vector<SimView> lap1, lap2;
};

/// Lap-2 frames (queries) against lap-1 frames. Same place: the lap-1 frame with the largest
/// ground-truth overlap (>= 0.5) with the query. Different place: pairs sharing < 5 % of their
/// views (both ways).
struct LoopFigures {
  int queries = 0;        ///< queries with a same-place lap-1 frame
  int top1_same = 0;      ///< queries whose best-scoring lap-1 frame overlaps >= 0.3
  double min_same = 1.0;  ///< lowest same-place score
  double mean_same = 0.0;
  double max_different = 0.0;  ///< highest different-place score
  double mean_different = 0.0;
  int different_pairs = 0;
  /// Fraction of (same-place pair, different-place pair) combinations ordered correctly.
  double ordered = 0.0;
};

/// Orbit queries: how often the keyframe database returns the query's own keyframe first,
/// and the smallest ratio of the own keyframe's score to the best other keyframe's.
struct OrbitFigures {
  int own_first = 0;
  int queries = 0;
  double min_ratio = 1e9;
};

/// Views of the evaluation scenes, rendered on first use (each test binary process).
const Views& views() {
  static const Views cached = [] {
    Views v;
    const test::SimViewRenderer room("room", 1);
    const StampedTrajectory orbit = makeSceneTrajectory(room.scene(), TrajectoryKind::kOrbit, 20.0);
    for (size_t i = 0; i + 4 < orbit.size(); i += 30) {
      v.orbit_keyframes.push_back(room.render(orbit[i].T_G_C));
      v.orbit_queries.push_back(room.render(orbit[i + 4].T_G_C));
    }
    const test::SimViewRenderer hall("hall", 1);
    const StampedTrajectory loop =
        makeSceneTrajectory(hall.scene(), TrajectoryKind::kLoop, 20.0, 2);
    const size_t half = loop.size() / 2;
    for (size_t i = 0; i < half; i += 40) v.lap1.push_back(hall.render(loop[i].T_G_C));
    for (size_t i = half + 20; i < loop.size(); i += 40) {
      v.lap2.push_back(hall.render(loop[i].T_G_C));
    }
    return v;
  }();
  return cached;
}

/// A vocabulary trained here on 30 frames of sim:yard along three of its paths (k = 10,
/// L = 6: every training descriptor ends up a word of its own).
const BinaryVocabulary& smallVocabulary() {
  static const BinaryVocabulary cached = [] {
    const test::SimViewRenderer yard("yard", 2);
    std::vector<std::vector<OrbDescriptor>> training;
    for (const TrajectoryKind kind :
         {TrajectoryKind::kLoop, TrajectoryKind::kOrbit, TrajectoryKind::kFigureEight}) {
      const StampedTrajectory t = makeSceneTrajectory(yard.scene(), kind, 20.0);
      for (size_t i = 0; i < 10; ++i) {
        training.push_back(yard.render(t[t.size() * i / 10].T_G_C).descriptors);
      }
    }
    BinaryVocabularyConfig config;
    config.num_threads = 2;
    return BinaryVocabulary::train(training, config);
  }();
  return cached;
}

class PlaceRecognitionTest : public ::testing::Test {
 protected:
  static OrbitFigures orbitFigures(const BinaryVocabulary& v) {
    KeyframeDatabase db;
    std::vector<BowVector> keyframes;
    for (size_t k = 0; k < views().orbit_keyframes.size(); ++k) {
      keyframes.push_back(v.transform(views().orbit_keyframes[k].descriptors));
      db.add(static_cast<KeyframeId>(k), keyframes.back());
    }
    OrbitFigures f;
    for (size_t q = 0; q < views().orbit_queries.size(); ++q) {
      const BowVector query = v.transform(views().orbit_queries[q].descriptors);
      const std::vector<PlaceCandidate> c = db.queryRelocalizationCandidates(query, 0);
      ++f.queries;
      f.own_first += !c.empty() && c[0].id == static_cast<KeyframeId>(q);
      double other = 0.0;
      for (size_t k = 0; k < keyframes.size(); ++k) {
        if (k != q) other = std::max(other, BinaryVocabulary::score(query, keyframes[k]));
      }
      f.min_ratio = std::min(f.min_ratio, BinaryVocabulary::score(query, keyframes[q]) / other);
    }
    return f;
  }

  static LoopFigures loopFigures(const BinaryVocabulary& v) {
    std::vector<BowVector> lap1;
    for (const SimView& view : views().lap1) lap1.push_back(v.transform(view.descriptors));
    LoopFigures f;
    std::vector<double> same, different;
    for (const SimView& query : views().lap2) {
      const BowVector q = v.transform(query.descriptors);
      double best_score = -1.0, best_overlap = 0.0, same_overlap = 0.5, same_score = -1.0;
      for (size_t i = 0; i < lap1.size(); ++i) {
        const double ab = viewOverlap(query, views().lap1[i]);
        const double ba = viewOverlap(views().lap1[i], query);
        const double overlap = std::min(ab, ba);
        const double s = BinaryVocabulary::score(q, lap1[i]);
        if (overlap >= same_overlap) {
          same_overlap = overlap;
          same_score = s;
        }
        if (s > best_score) {
          best_score = s;
          best_overlap = overlap;
        }
        if (std::max(ab, ba) < 0.05) {
          different.push_back(s);
        }
      }
      if (same_score < 0.0) continue;
      ++f.queries;
      f.top1_same += best_overlap >= 0.3;
      same.push_back(same_score);
    }
    size_t ordered = 0;
    for (const double a : same) {
      f.min_same = std::min(f.min_same, a);
      f.mean_same += a / static_cast<double>(same.size());
      for (const double b : different) ordered += a > b;
    }
    for (const double b : different) {
      f.max_different = std::max(f.max_different, b);
      f.mean_different += b / static_cast<double>(different.size());
    }
    f.different_pairs = static_cast<int>(different.size());
    f.ordered = static_cast<double>(ordered) / static_cast<double>(same.size() * different.size());
    return f;
  }

  /// Prints the figures (quoted in the README) and checks them: the own keyframe first (by
  /// a margin: the next keyframe, 0.7 m on, still shares most of the view), the same place
  /// first on the second lap, at least 99 % of (same-place, different-place) score pairs
  /// ordered (measured: all of them), and the mean same-place score `min_mean_ratio` times
  /// the mean different-place score. `orbit_misses`: room-orbit keyframes allowed not to rank
  /// themselves first (each then still scores >= 0.95 of the best).
  static void check(const char* name, const BinaryVocabulary& v, double min_mean_ratio,
                    int orbit_misses = 0) {
    const OrbitFigures o = orbitFigures(v);
    const LoopFigures f = loopFigures(v);
    std::printf(
        "[ %s vocabulary, %zu words ] room orbit: own keyframe first %d/%d, own/next score >= "
        "%.2f | hall, two laps: top-1 same place %d/%d; same-place score min %.4f mean %.4f; "
        "different-place (%d pairs) max %.4f mean %.4f; ordered %.4f\n",
        name, v.wordCount(), o.own_first, o.queries, o.min_ratio, f.top1_same, f.queries,
        f.min_same, f.mean_same, f.different_pairs, f.max_different, f.mean_different, f.ordered);
    EXPECT_GE(o.queries, 12);
    EXPECT_GE(o.own_first, o.queries - orbit_misses) << name;
    EXPECT_GT(o.min_ratio, orbit_misses > 0 ? 0.95 : 1.1) << name;
    EXPECT_GE(f.queries, 15) << name;
    EXPECT_GE(f.different_pairs, 200) << name;
    EXPECT_EQ(f.top1_same, f.queries) << name;
    EXPECT_GE(f.ordered, 0.99) << name;
    EXPECT_GT(f.mean_same, min_mean_ratio * f.mean_different) << name;
  }
};

TEST(ViewOverlapTest, IsOneForTheSameViewNearOneForASmallStepAndZeroForATurnedView) {
  const test::SimViewRenderer hall("hall", 1);
  const StampedTrajectory loop = makeSceneTrajectory(hall.scene(), TrajectoryKind::kLoop, 20.0);
  const Transformationd& T_G_C = loop[100].T_G_C;
  const SimView a = hall.render(T_G_C);
  const SimView step = hall.render(loop[104].T_G_C);  // 0.2 s later
  const SimView turned = hall.render(Transformationd(
      Eigen::AngleAxisd(std::numbers::pi, Eigen::Vector3d::UnitZ()).toRotationMatrix() *
          T_G_C.rotationMatrix(),
      T_G_C.translation()));
  EXPECT_NEAR(viewOverlap(a, a), 1.0, 1e-12);
  EXPECT_GT(viewOverlap(a, step), 0.8);
  EXPECT_LT(viewOverlap(a, step), 1.0);
  EXPECT_EQ(viewOverlap(a, turned), 0.0);  // 78 degree field of view
  EXPECT_EQ(viewOverlap(turned, a), 0.0);
}

TEST_F(PlaceRecognitionTest, SmallVocabularyTrainedOnTheYardRecognisesPlaces) {
  // The yard frames it is trained on are rendered by Embree, whose kernels round per CPU
  // instruction set: on an AVX2-only EPYC 12 of 13 room keyframes ranked themselves first
  // (the 13th at 0.989 of the best), on the earlier machines 13 of 13 with a 1.1 margin.
  check("small (30 yard frames)", smallVocabulary(), 1.5, /*orbit_misses=*/1);
}

TEST_F(PlaceRecognitionTest, BuildTimeVocabularyRecognisesPlaces) {
  const test::BuildTimeVocabulary built = test::loadBuildTimeVocabulary();
  if (!built.skip_reason.empty()) GTEST_SKIP() << built.skip_reason;
  ASSERT_TRUE(built.vocabulary.has_value()) << built.error;
  check("build-time", *built.vocabulary, 3.0);
}

}  // namespace
}  // namespace cblox
