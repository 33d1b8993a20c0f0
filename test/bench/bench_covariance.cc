// Conditional covariance extraction (issue 6, item 6): per-pair constrained ordering (the
// paper's method), AMD + Kaess & Dellaert recovery, batch mode, sparse forward solves
// (SparseSolveCovarianceSolver; nested dissection, and AMD for comparison) and
// ceres::Covariance, on closed-loop synthetic BA problems
// (default; test/covariance/loop_scene.h: 50 landmarks per keyframe, 3-8 observers each, 30%
// re-observed on the other lap) or, with --scene, on REAL sparse-SLAM BA problems: the SLAM
// system runs in-process on the simulator scene (trajectory loop, --laps laps, at --rate) and
// when its map first reaches each of --sizes keyframes (after waitUntilIdle) the whole map is
// snapshotted (buildMapBaProblem, first keyframe fixed), linearised with the Huber reweighting
// (as the keyframe covariance service does) and measured like a synthetic size; if the run
// ends below the largest size, the final map is measured too.
//
//   cblox-bench-covariance [--sizes 50,200,500,1000] [--pairs 20] [--far-pairs N]
//                          [--ceres-limit-s 60] [--ceres-max-keyframes N] [--laps 2]
//                          [--landmarks-per-keyframe 50] [--big-batch 100] [--seed 1]
//                          [--scene room|hall|town] [--rate HZ] [--vocabulary FILE]
//
// Pairs: --pairs random covisible pairs (S block non-zero) plus --far-pairs pairs (default 0
// on synthetic scenes, 4 on --scene) of a random keyframe and one at the largest hop
// distance from it in S's block graph.
// Per size: building S (linearisation excluded, printed apart), per-pair constrained
// ordering (default kAuto, forced supernodal, forced simplicial factor), Kaess (one factorisation,
// then per pair with an empty cache and amortised with the cache kept), batch (all pairs in one
// call), and once more with --big-batch covisible pairs (how the batch cost per pair
// amortises), sparse solve (factor once; per pair in its own call; all pairs in one call),
// ceres::Covariance (SPARSE_QR, one Compute for one pair and one for all pairs; skipped
// where it is predicted to exceed --ceres-limit-s from the previous size's time, or above
// --ceres-max-keyframes). All methods' Sigma_{i|j} are cross-checked against batch mode.
// Building S, the batch calls, the sparse solve's pairs and the breakdown are the least of 3
// runs (the machine is shared); per-pair figures are averages over the pairs; ceres runs
// once, single-threaded.

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <deque>
#include <functional>
#include <limits>
#include <memory>
#include <optional>
#include <random>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include <CLI/CLI.hpp>

#include "core/covariance/batch_covariance_solver.h"
#include "core/covariance/block_ordering.h"
#include "core/covariance/constrained_ordering_solver.h"
#include "core/covariance/kaess_recovery_solver.h"
#include "core/covariance/sparse_solve_solver.h"
#include "core/optimization/cholmod_support.h"
#include "daemon/common/cli.h"
#include "test/covariance/ceres_reference.h"
#include "test/covariance/loop_scene.h"

#ifdef CBLOX_BENCH_COVARIANCE_SLAM
#include "core/tracking/map_ba_problem.h"
#include "core/tracking/slam_system.h"
#include "drivers/open_frame_source.h"
#endif

namespace {

using namespace cblox;
using Clock = std::chrono::steady_clock;

double msSince(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

template <typename F>
double timeMs(F&& f) {
  const auto t0 = Clock::now();
  f();
  return msSince(t0);
}

// Least of `repeats` runs (the machine is shared: the minimum is the least disturbed).
template <typename F>
double minTimeMs(int repeats, F&& f) {
  double best = HUGE_VAL;
  for (int r = 0; r < repeats; ++r) best = std::min(best, timeMs(f));
  return best;
}

// The sparse solve with one configuration (ordering, kernel).
struct SparseTimes {
  double factor_ms = 0;
  double pair_ms = 0;   // each pair in its own compute() call
  double batch_ms = 0;  // all pairs in one call (keyframes solved once)
  double reach = 0;     // mean reached columns per solved keyframe
  double mflop = 0;     // mean Mflop of a keyframe's solve
};

struct Options {
  std::vector<int> sizes = {50, 200, 500, 1000};
  int pairs = 20;
  int far_pairs = -1;  // -1: 0 on synthetic scenes, 4 on --scene
  double ceres_limit_s = 60.0;
  int ceres_max_keyframes = 1000000;
  std::uint32_t seed = 1;
  int laps = 2;
  int landmarks_per_keyframe = 50;
  int big_batch = 100;  // pairs of the extra batch-mode measurement (0 = none)
  std::string scene;    // empty: synthetic loop scenes
  double rate_hz = -1;  // --scene: frame rate fed to the SLAM (< 0: the source's; 0: no wait)
  std::string vocabulary;
};

/// Parses the command line into *o. Returns the exit status when the program is to stop
/// (--help: 0, a usage error: 2).
std::optional<int> parse(int argc, char** argv, Options* o) {
#ifdef CBLOX_DEFAULT_VOCABULARY
  o->vocabulary = CBLOX_DEFAULT_VOCABULARY;
#endif
  CLI::App app{
      "cblox-bench-covariance: conditional covariance extraction (constrained ordering, Kaess,\n"
      "batch, sparse solve, ceres::Covariance) on synthetic loop scenes or, with --scene, on BA\n"
      "problems of the sparse SLAM running on the simulator.",
      "cblox-bench-covariance"};
  app.add_option("--sizes", o->sizes, "keyframes of the measured problems (each >= 4)")
      ->delimiter(',')
      ->allow_extra_args(false)
      ->check(CLI::Range(4, std::numeric_limits<int>::max()))
      ->type_name("N[,N...]");
  app.add_option("--pairs", o->pairs, "random covisible pairs")
      ->check(finiteNumber(NumberBound::kPositive))
      ->capture_default_str();
  app.add_option("--far-pairs", o->far_pairs,
                 "pairs of a keyframe and the one farthest from it (default: 0; 4 with --scene)")
      ->type_name("N");
  app.add_option("--ceres-limit-s", o->ceres_limit_s,
                 "skip ceres where it is predicted to take longer")
      ->capture_default_str();
  app.add_option("--ceres-max-keyframes", o->ceres_max_keyframes, "skip ceres above this size")
      ->type_name("N");
  app.add_option("--laps", o->laps, "laps of the scene")
      ->check(finiteNumber(NumberBound::kPositive))
      ->capture_default_str();
  app.add_option("--landmarks-per-keyframe", o->landmarks_per_keyframe, "synthetic scenes")
      ->check(finiteNumber(NumberBound::kPositive))
      ->capture_default_str();
  app.add_option("--big-batch", o->big_batch, "pairs of the extra batch measurement (0: none)")
      ->check(finiteNumber(NumberBound::kNonNegative))
      ->capture_default_str();
  app.add_option("--seed", o->seed, "random pairs")->capture_default_str();
  app.add_option("--scene", o->scene, "room | hall | town: BA problems of the sparse SLAM");
  app.add_option("--rate", o->rate_hz,
                 "--scene: frames per second fed to the SLAM (default: the source's; 0: no wait)")
      ->type_name("HZ");
  app.add_option("--vocabulary", o->vocabulary, "--scene: vocabulary file")->capture_default_str();
  if (const std::optional<int> code = parseCommandLine(app, argc, argv)) return code;
  if (o->far_pairs < 0) o->far_pairs = o->scene.empty() ? 0 : 4;
  std::sort(o->sizes.begin(), o->sizes.end());
  return std::nullopt;
}

// Random covisible pairs (i, j), i != j: a random block and a random neighbour of it.
std::vector<KeyframePair> covisiblePairs(const ReducedCameraMatrix& S, int n, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> block_of(0, S.numBlocks() - 1);
  std::vector<KeyframePair> pairs;
  for (int attempt = 0; static_cast<int>(pairs.size()) < n && attempt < 1000 * n; ++attempt) {
    const int c = block_of(rng);
    const int begin = S.block_col_ptr[c];
    const int count = S.block_col_ptr[c + 1] - begin;
    const int r = S.block_row_index[begin + std::uniform_int_distribution<int>(0, count - 1)(rng)];
    if (r != c) pairs.push_back({S.keyframe_ids[c], S.keyframe_ids[r]});
  }
  return pairs;
}

// Far pairs (i, j): a random block i and a block at the largest hop distance from it in S's
// block graph (breadth-first search). *hops gets the mean distance.
std::vector<KeyframePair> farPairs(const ReducedCameraMatrix& S, int n, std::uint32_t seed,
                                   double* hops) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> block_of(0, S.numBlocks() - 1);
  std::vector<KeyframePair> pairs;
  double total = 0.0;
  for (int p = 0; p < n && S.numBlocks() > 1; ++p) {
    const int start = block_of(rng);
    std::vector<int> distance(S.numBlocks(), -1);
    std::deque<int> queue = {start};
    distance[start] = 0;
    int last = start;
    while (!queue.empty()) {
      last = queue.front();
      queue.pop_front();
      for (int k = S.block_col_ptr[last]; k < S.block_col_ptr[last + 1]; ++k) {
        const int r = S.block_row_index[k];
        if (distance[r] < 0) {
          distance[r] = distance[last] + 1;
          queue.push_back(r);
        }
      }
    }
    if (last == start) continue;
    pairs.push_back({S.keyframe_ids[start], S.keyframe_ids[last]});
    total += distance[last];
  }
  *hops = pairs.empty() ? 0.0 : total / static_cast<double>(pairs.size());
  return pairs;
}

double worstDifference(const std::vector<ConditionalCovariance>& a,
                       const std::vector<ConditionalCovariance>& b) {
  double worst = 0.0;
  for (size_t p = 0; p < a.size() && p < b.size(); ++p) {
    if (!a[p].ok || !b[p].ok) return HUGE_VAL;
    worst = std::max(worst, (a[p].sigma - b[p].sigma).norm() / b[p].sigma.norm());
  }
  return a.size() == b.size() ? worst : HUGE_VAL;
}

struct Row {
  std::string label;
  int keyframes = 0;
  int landmarks = 0;
  int observations = 0;
  int pairs = 0;
  int far_pairs = 0;
  double far_hops = 0;
  double blocks_per_column = 0;
  int columns = 0;  // 6 x free keyframes: the size of S
  double linearize_ms = 0;
  double reduce_ms = 0;
  double per_pair_ms = 0;
  double per_pair_supernodal_ms = 0;
  double per_pair_simplicial_ms = 0;
  double kaess_factor_ms = 0;
  double kaess_pair_cold_ms = 0;
  double kaess_pair_cached_ms = 0;
  double batch_ms = 0;
  double big_batch_ms = -1;
  int big_batch_keyframes = 0;
  SparseTimes sparse;           // the defaults (nested dissection, AVX2 kernel)
  SparseTimes sparse_amd;       // the AMD ordering, for comparison
  SparseTimes sparse_portable;  // the portable kernel, for comparison
  double amd_nnz = 0;           // nnz(L) and Mflop of the AMD factorisation
  double amd_mflop = 0;
  double ceres_one_ms = -1;  // < 0: skipped
  double ceres_all_ms = -1;
  bool ceres_failed = false;  // Compute returned false (rank-deficient Jacobian)
  double camd_ms = 0;
  double analyze_ms = 0;
  double factorize_ms = 0;
  double factor_nnz = 0;
  double factor_mflop = 0;
  double direct_read_ms = 0;
  double change_factor_ms = 0;
  double worst_difference = 0;
};

// Symbolic analysis of S with `perm` forced: nnz(L) and flops of its factorisation.
void analyzeOnly(const ReducedCameraMatrix& S, const std::vector<int>& perm, double* nnz,
                 double* mflop) {
  CholmodCommon common;
  CholmodSymmetricMatrix A(S.matrix);
  cholmod_common* c = common.get();
  c->nmethods = 1;
  c->method[0].ordering = CHOLMOD_GIVEN;
  c->postorder = 0;
  std::vector<int> p = perm;
  cholmod_factor* L = cholmod_analyze_p(A.get(), p.data(), nullptr, 0, c);
  *nnz = c->lnz;
  *mflop = c->fl / 1e6;
  cholmod_free_factor(&L, c);
}

// All measurements on one BA problem. `ceres_prediction_s`: predicted time of ceres on this
// problem (ceres is skipped above --ceres-limit-s); set to its measured time on return.
Row runProblem(const BundleAdjustmentProblem& problem, const BaLinearizationConfig& lin_config,
               const Options& o, double* ceres_prediction_s) {
  Row row;
  row.keyframes = static_cast<int>(problem.keyframes.size());
  row.landmarks = static_cast<int>(problem.landmarks.size());
  row.observations = static_cast<int>(problem.observations.size());
  BaLinearization lin;
  row.linearize_ms = timeMs([&] { lin = linearizeBundleAdjustment(problem, {}, lin_config); });
  ReducedCameraMatrix S;
  row.reduce_ms = minTimeMs(3, [&] { S = reduceCameraMatrix(lin); });
  row.blocks_per_column = static_cast<double>(S.block_col_ptr.back()) / S.numBlocks();
  row.columns = static_cast<int>(S.matrix.rows());
  std::vector<KeyframePair> pairs = covisiblePairs(S, o.pairs, o.seed + 7);
  const std::vector<KeyframePair> far = farPairs(S, o.far_pairs, o.seed + 13, &row.far_hops);
  pairs.insert(pairs.end(), far.begin(), far.end());
  row.pairs = static_cast<int>(pairs.size());
  row.far_pairs = static_cast<int>(far.size());
  const double n = static_cast<double>(pairs.size());
  analyzeOnly(S, expandBlockPermutation(blockAmdOrdering(S)), &row.amd_nnz, &row.amd_mflop);

  BatchCovarianceSolver batch(S);
  std::vector<ConditionalCovariance> reference;
  row.batch_ms = minTimeMs(3, [&] { reference = batch.compute(pairs); });
  for (const ConditionalCovariance& r : reference) {
    if (!r.ok) {
      std::fprintf(stderr, "batch failed on pair (%lu, %lu): %s\n", static_cast<unsigned long>(r.i),
                   static_cast<unsigned long>(r.j), r.error.c_str());
      row.worst_difference = HUGE_VAL;
    }
  }

  if (o.big_batch > 0) {
    const std::vector<KeyframePair> big = covisiblePairs(S, o.big_batch, o.seed + 11);
    std::vector<ConditionalCovariance> big_result;
    row.big_batch_ms = minTimeMs(3, [&] { big_result = batch.compute(big); });
    std::vector<std::uint64_t> ids;
    for (const KeyframePair& p : big) ids.insert(ids.end(), {p.i, p.j});
    std::sort(ids.begin(), ids.end());
    row.big_batch_keyframes = static_cast<int>(std::unique(ids.begin(), ids.end()) - ids.begin());
    for (const ConditionalCovariance& r : big_result) {
      if (!r.ok) row.worst_difference = HUGE_VAL;
    }
  }

  // Sparse solve: factor once, then each pair in its own call, then all pairs in one call;
  // with the defaults, with the AMD ordering and with the portable kernel.
  std::vector<ConditionalCovariance> got(pairs.size());
  auto sparseTimes = [&](const SparseSolveCovarianceSolverConfig& config) {
    SparseTimes t;
    std::unique_ptr<SparseSolveCovarianceSolver> sparse;
    t.factor_ms =
        timeMs([&] { sparse = std::make_unique<SparseSolveCovarianceSolver>(S, config); });
    std::int64_t reached = 0;
    double flops = 0.0;
    int solved = 0;
    bool first = true;  // the work is counted on the first of the 3 runs
    t.pair_ms = minTimeMs(3,
                          [&] {
                            for (size_t p = 0; p < pairs.size(); ++p) {  // each in its own call
                              got[p] = sparse->compute(pairs[p].i, pairs[p].j);
                              if (!first) continue;
                              reached += sparse->stats().reached_columns;
                              flops += sparse->stats().flops;
                              solved += sparse->stats().keyframes_solved;
                            }
                            first = false;
                          }) /
                n;
    row.worst_difference = std::max(row.worst_difference, worstDifference(got, reference));
    t.reach = static_cast<double>(reached) / std::max(1, solved);
    t.mflop = flops / std::max(1, solved) / 1e6;
    t.batch_ms = minTimeMs(3, [&] { got = sparse->compute(pairs); });
    row.worst_difference = std::max(row.worst_difference, worstDifference(got, reference));
    return t;
  };
  row.sparse = sparseTimes({});
  SparseSolveCovarianceSolverConfig amd, portable;
  amd.ordering = BlockOrdering::kAmd;
  portable.vectorized = false;
  row.sparse_amd = sparseTimes(amd);
  row.sparse_portable = sparseTimes(portable);

  // Per-pair constrained ordering with the default factor kind (kAuto) and both forced.
  auto perPairMs = [&](CholmodFactorKind kind) {
    CholmodFactorConfig factor;
    factor.kind = kind;
    ConstrainedOrderingSolver solver(S, {factor});
    const double t = timeMs([&] {
      for (size_t p = 0; p < pairs.size(); ++p) got[p] = solver.compute(pairs[p].i, pairs[p].j);
    });
    row.worst_difference = std::max(row.worst_difference, worstDifference(got, reference));
    return t / n;
  };
  row.per_pair_ms = perPairMs(CholmodFactorKind::kAuto);
  row.per_pair_supernodal_ms = perPairMs(CholmodFactorKind::kSupernodal);
  row.per_pair_simplicial_ms = perPairMs(CholmodFactorKind::kSimplicial);

  std::unique_ptr<KaessRecoverySolver> kaess;
  row.kaess_factor_ms = timeMs([&] {
    kaess = std::make_unique<KaessRecoverySolver>(S, KaessRecoverySolverConfig{{}, false});
  });
  row.kaess_pair_cold_ms = timeMs([&] { got = kaess->compute(pairs); }) / n;
  row.worst_difference = std::max(row.worst_difference, worstDifference(got, reference));
  KaessRecoverySolver kaess_cached(S);
  row.kaess_pair_cached_ms = timeMs([&] { got = kaess_cached.compute(pairs); }) / n;
  row.worst_difference = std::max(row.worst_difference, worstDifference(got, reference));

  // Reading the trailing 12 columns: directly from the supernodes vs converting the factor.
  {
    CholmodCommon common;
    CholmodSymmetricMatrix A(S.matrix);
    std::vector<int> constraint(S.numBlocks(), 0);
    constraint[S.blockOf(pairs[0].i)] = 1;
    constraint[S.blockOf(pairs[0].j)] = 2;
    std::vector<int> perm;
    row.camd_ms =
        timeMs([&] { perm = expandBlockPermutation(constrainedBlockOrdering(S, constraint)); });
    {
      // Breakdown of one per-pair factorisation (what factorizeWithPermutation does).
      cholmod_common* c = common.get();
      c->nmethods = 1;
      c->method[0].ordering = CHOLMOD_GIVEN;
      c->postorder = 0;
      c->supernodal = CHOLMOD_SUPERNODAL;
      row.analyze_ms = row.factorize_ms = HUGE_VAL;
      for (int repeat = 0; repeat < 3; ++repeat) {
        cholmod_factor* L = nullptr;
        row.analyze_ms =
            std::min(row.analyze_ms,
                     timeMs([&] { L = cholmod_analyze_p(A.get(), perm.data(), nullptr, 0, c); }));
        row.factor_nnz = c->lnz;
        row.factor_mflop = c->fl / 1e6;
        row.factorize_ms =
            std::min(row.factorize_ms, timeMs([&] { cholmod_factorize(A.get(), L, c); }));
        cholmod_free_factor(&L, c);
      }
    }
    CholmodFactorConfig supernodal;
    supernodal.kind = CholmodFactorKind::kSupernodal;
    CholmodFactorOutcome f = factorizeWithPermutation(common, A, perm, supernodal, S.keyframe_ids);
    if (f.ok) {
      Eigen::MatrixXd direct, converted;
      row.direct_read_ms = timeMs([&] { direct = trailingFactorBlock(*f.factor.get(), 12); });
      row.change_factor_ms = timeMs([&] {
        cholmod_change_factor(CHOLMOD_REAL, 1, 0, 1, 1, f.factor.get(), common.get());
        converted = trailingFactorBlock(*f.factor.get(), 12);
      });
      if ((direct - converted).norm() > 1e-12 * direct.norm()) row.worst_difference = HUGE_VAL;
    } else {
      row.worst_difference = HUGE_VAL;
    }
  }

  // ceres::Covariance (SPARSE_QR) on the same problem.
  const bool ceres_allowed =
      row.keyframes <= o.ceres_max_keyframes && *ceres_prediction_s <= o.ceres_limit_s;
  if (ceres_allowed) {
    test::CeresCovarianceReference ceres_reference(problem, lin, lin_config);
    std::vector<ConditionalCovariance> c1, call;
    row.ceres_one_ms = timeMs([&] {
      c1 = ceres_reference.compute(std::span<const KeyframePair>(pairs).first(1), ceres::SPARSE_QR);
    });
    row.ceres_all_ms = timeMs([&] { call = ceres_reference.compute(pairs, ceres::SPARSE_QR); });
    // Ceres refuses a rank-deficient full Jacobian (e.g. a landmark without parallax, which
    // reduceCameraMatrix drops): reported as failed, not compared.
    row.ceres_failed = c1.empty() || call.empty();
    if (!row.ceres_failed) {
      row.worst_difference = std::max(row.worst_difference, worstDifference(call, reference));
    }
    *ceres_prediction_s = row.ceres_all_ms / 1000.0;
  } else {
    *ceres_prediction_s = HUGE_VAL;
  }
  return row;
}

// Ceres' time on the next problem from the previous one: ~ (size ratio)^1.5.
void predictCeres(int previous_keyframes, int keyframes, double* ceres_prediction_s) {
  if (previous_keyframes > 0 && std::isfinite(*ceres_prediction_s)) {
    *ceres_prediction_s *= std::pow(static_cast<double>(keyframes) / previous_keyframes, 1.5);
  }
}

std::string ratio(double ceres_ms, double ms) {
  if (ceres_ms < 0) return "-";
  char b[32];
  std::snprintf(b, sizeof(b), "%.0fx", ceres_ms / ms);
  return b;
}

std::string ms(double v) {
  if (v < 0) return "skipped";
  char b[32];
  std::snprintf(b, sizeof(b), v < 10 ? "%.3f" : "%.1f", v);
  return b;
}

void printTables(const std::vector<Row>& rows, const Options& o) {
  std::printf(
      "| problem | keyframes | landmarks | obs | S blocks/col | nnz(L) AMD | Mflop AMD | "
      "sparse-solve reach cols/keyframe | Mflop/keyframe solve | linearize | build S |\n");
  std::printf("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
  for (const Row& r : rows) {
    std::printf("| %s | %d | %d | %d | %.1f | %.0f | %.1f | %.0f (of %d) | %.2f | %s | %s |\n",
                r.label.c_str(), r.keyframes, r.landmarks, r.observations, r.blocks_per_column,
                r.amd_nnz, r.amd_mflop, r.sparse.reach, r.columns, r.sparse.mflop,
                ms(r.linearize_ms).c_str(), ms(r.reduce_ms).c_str());
  }
  std::printf(
      "\n| problem | keyframes | pairs (far, mean hops) | per-pair CAMD (kAuto) /pair | "
      "per-pair supernodal /pair | per-pair simplicial /pair | Kaess factor once | "
      "Kaess /pair (cold) | Kaess /pair (cached) | batch /batch | batch /pair | "
      "sparse factor once | sparse /pair (own call) | sparse /pair (one call) | ceres 1 pair | "
      "ceres all pairs | ceres/per-pair | ceres/batch | ceres/sparse (own call) | "
      "max rel diff |\n");
  std::printf(
      "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"
      "---:|---:|---:|\n");
  for (const Row& r : rows) {
    const double n = r.pairs;
    std::printf(
        "| %s | %d | %d (%d, %.1f) | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | "
        "%s | %s | %s | %s | %.1e |\n",
        r.label.c_str(), r.keyframes, r.pairs, r.far_pairs, r.far_hops, ms(r.per_pair_ms).c_str(),
        ms(r.per_pair_supernodal_ms).c_str(), ms(r.per_pair_simplicial_ms).c_str(),
        ms(r.kaess_factor_ms).c_str(), ms(r.kaess_pair_cold_ms).c_str(),
        ms(r.kaess_pair_cached_ms).c_str(), ms(r.batch_ms).c_str(), ms(r.batch_ms / n).c_str(),
        ms(r.sparse.factor_ms).c_str(), ms(r.sparse.pair_ms).c_str(),
        ms(r.sparse.batch_ms / n).c_str(),
        r.ceres_failed ? ("failed in " + ms(r.ceres_one_ms)).c_str() : ms(r.ceres_one_ms).c_str(),
        r.ceres_failed ? ("failed in " + ms(r.ceres_all_ms)).c_str() : ms(r.ceres_all_ms).c_str(),
        ratio(r.ceres_failed ? -1 : r.ceres_one_ms, r.per_pair_ms).c_str(),
        ratio(r.ceres_failed ? -1 : r.ceres_all_ms, r.batch_ms).c_str(),
        ratio(r.ceres_failed ? -1 : r.ceres_one_ms, r.sparse.pair_ms).c_str(), r.worst_difference);
  }
  std::printf(
      "\nThe sparse solve's block ordering and kernel (same pairs, same run; the kernel is "
      "AVX2+FMA where the CPU has both):\n\n"
      "| problem | keyframes | ordering, kernel | factor once | /pair (own call) | /pair (one "
      "call) | reach cols/keyframe | Mflop/keyframe solve |\n"
      "|---|---:|---|---:|---:|---:|---:|---:|\n");
  for (const Row& r : rows) {
    for (const auto& [name, t] : {std::pair{"nested dissection, vectorized (default)", r.sparse},
                                  std::pair{"amd, vectorized", r.sparse_amd},
                                  std::pair{"nested dissection, portable", r.sparse_portable}}) {
      std::printf("| %s | %d | %s | %s | %s | %s | %.0f (of %d) | %.2f |\n", r.label.c_str(),
                  r.keyframes, name, ms(t.factor_ms).c_str(), ms(t.pair_ms).c_str(),
                  ms(t.batch_ms / r.pairs).c_str(), t.reach, r.columns, t.mflop);
    }
  }
  if (o.big_batch > 0) {
    std::printf("\nBatch mode with %d covisible pairs:\n\n", o.big_batch);
    std::printf("| problem | keyframes | distinct keyframes constrained last | /batch | /pair |\n");
    std::printf("|---|---:|---:|---:|---:|\n");
    for (const Row& r : rows) {
      std::printf("| %s | %d | %d | %s | %s |\n", r.label.c_str(), r.keyframes,
                  r.big_batch_keyframes, ms(r.big_batch_ms).c_str(),
                  ms(r.big_batch_ms / o.big_batch).c_str());
    }
  }
  std::printf("\nOne per-pair factorisation (supernodal), broken down (least of 3 runs):\n\n");
  std::printf(
      "| problem | keyframes | CAMD (block level) | cholmod_analyze_p | cholmod_factorize | "
      "nnz(L) | Mflop | trailing 12x12 read from supernodes | change_factor + read |\n");
  std::printf("|---|---:|---:|---:|---:|---:|---:|---:|---:|\n");
  for (const Row& r : rows) {
    std::printf("| %s | %d | %s | %s | %s | %.0f | %.1f | %s | %s |\n", r.label.c_str(),
                r.keyframes, ms(r.camd_ms).c_str(), ms(r.analyze_ms).c_str(),
                ms(r.factorize_ms).c_str(), r.factor_nnz, r.factor_mflop,
                ms(r.direct_read_ms).c_str(), ms(r.change_factor_ms).c_str());
  }
}

int runSynthetic(const Options& o, std::vector<Row>* rows) {
  std::printf(
      "cblox-bench-covariance: %d random covisible + %d far pairs per size, loop scenes "
      "(%d laps, %d landmarks/keyframe), times in ms\n\n",
      o.pairs, o.far_pairs, o.laps, o.landmarks_per_keyframe);
  double ceres_prediction_s = 0.0;
  int previous = 0;
  for (const int size : o.sizes) {
    predictCeres(previous, size, &ceres_prediction_s);
    std::fprintf(stderr, "size %d ...\n", size);
    test::LoopSceneOptions scene_options;
    scene_options.keyframes = size;
    scene_options.seed = o.seed;
    scene_options.laps = o.laps;
    scene_options.landmarks_per_keyframe = o.landmarks_per_keyframe;
    const test::BaScene scene = test::makeLoopBaScene(scene_options);
    rows->push_back(runProblem(scene.problem, {}, o, &ceres_prediction_s));
    rows->back().label = "synthetic loop";
    previous = size;
  }
  return 0;
}

#ifdef CBLOX_BENCH_COVARIANCE_SLAM
int runScene(const Options& o, std::vector<Row>* rows) {
  std::string error;
  const auto vocabulary = BinaryVocabulary::load(o.vocabulary, &error);
  if (!vocabulary) {
    std::fprintf(stderr, "vocabulary: %s\n", error.c_str());
    return 2;
  }
  SourceConfig options;
  options.trajectory = "loop";
  options.laps = o.laps;
  auto source = openFrameSource("sim:" + o.scene, options, &error);
  if (!source) {
    std::fprintf(stderr, "%s\n", error.c_str());
    return 2;
  }
  const SourceInfo info = source->info();
  if (!info.stereo) {
    std::fprintf(stderr, "sim:%s delivers no stereo pair\n", o.scene.c_str());
    return 2;
  }
  const double rate = o.rate_hz < 0 ? info.rate_hz : o.rate_hz;
  const size_t total = info.frame_count.value_or(0);
  std::printf(
      "cblox-bench-covariance: sim:%s, trajectory loop, %d laps, %zu frames at %.0f Hz; "
      "snapshots at %s keyframes; %d random covisible + %d far pairs per snapshot; BA "
      "linearised with Huber reweighting; times in ms\n\n",
      o.scene.c_str(), o.laps, total, rate,
      [&] {
        std::string s;
        for (const int k : o.sizes) s += (s.empty() ? "" : ",") + std::to_string(k);
        return s;
      }()
          .c_str(),
      o.pairs, o.far_pairs);
  const RectifiedStereoCalibration& calibration = *info.stereo;
  const TrackingCamera camera = makeTrackingCamera(calibration.intrinsics, calibration.baseline_m);
  SlamSystem slam(camera, SlamSystemConfig{}, &*vocabulary);

  auto snapshot = [&](const char* when, double* ceres_prediction_s, int* previous) {
    slam.waitUntilIdle();
    const MapBaProblem map_problem = buildMapBaProblem(slam.map(), camera, slam.pyramid(), nullptr);
    const int k = static_cast<int>(map_problem.problem.keyframes.size());
    std::fprintf(stderr, "\nsnapshot (%s): %d keyframes, %zu landmarks, %zu observations\n", when,
                 k, map_problem.problem.landmarks.size(), map_problem.problem.observations.size());
    predictCeres(*previous, k, ceres_prediction_s);
    try {
      rows->push_back(
          runProblem(map_problem.problem, BaLinearizationConfig{true}, o, ceres_prediction_s));
      rows->back().label = "sim:" + o.scene + " " + when;
    } catch (const std::exception& e) {
      std::fprintf(stderr, "snapshot failed: %s\n", e.what());
    }
    *previous = k;
  };

  double ceres_prediction_s = 0.0;
  int previous = 0;
  size_t next = 0;
  CaptureFrame frame;
  size_t i = 0;
  const auto start = Clock::now();
  auto schedule = start;  // frame i is due at schedule + i / rate (shifted by snapshots)
  double snapshot_s = 0.0;
  while (next < o.sizes.size() && source->next(&frame, &error) == FrameSource::Status::kFrame) {
    if (rate > 0.0) {
      std::this_thread::sleep_until(schedule + std::chrono::duration_cast<Clock::duration>(
                                                   std::chrono::duration<double>(i / rate)));
    }
    slam.trackStereo(static_cast<uint64_t>(frame.frame_id), frame.timestamp_ns, frame.left,
                     frame.right,
                     frame.T_G_C ? std::optional(frame.T_G_C->inverse()) : std::nullopt);
    ++i;
    if (static_cast<int>(slam.map().numKeyframes()) >= o.sizes[next]) {
      const auto t0 = Clock::now();
      snapshot("at frame", &ceres_prediction_s, &previous);
      rows->back().label += " " + std::to_string(i);
      while (next < o.sizes.size() &&
             static_cast<int>(slam.map().numKeyframes()) >= o.sizes[next]) {
        ++next;
      }
      schedule += Clock::now() - t0;
      snapshot_s += std::chrono::duration<double>(Clock::now() - t0).count();
    }
    if (i % 50 == 0) {
      const double elapsed =
          std::chrono::duration<double>(Clock::now() - start).count() - snapshot_s;
      std::fprintf(stderr, "\rframe %zu/%zu (%.1f Hz), %zu keyframes, ETA %.0f s   ", i, total,
                   i / elapsed, slam.map().numKeyframes(),
                   total > i ? elapsed / i * (total - i) : 0.0);
    }
  }
  if (next < o.sizes.size()) {
    std::fprintf(stderr, "\nthe run ended with %zu keyframes (< %d): measuring the final map\n",
                 slam.map().numKeyframes(), o.sizes[next]);
    snapshot("final", &ceres_prediction_s, &previous);
  }
  slam.stop();
  std::fprintf(stderr, "\n");
  return 0;
}
#endif

}  // namespace

int main(int argc, char** argv) {
  Options o;
  if (const std::optional<int> code = parse(argc, argv, &o)) return *code;
  std::vector<Row> rows;
  int status = 0;
  if (o.scene.empty()) {
    status = runSynthetic(o, &rows);
  } else {
#ifdef CBLOX_BENCH_COVARIANCE_SLAM
    status = runScene(o, &rows);
#else
    std::fprintf(stderr, "--scene needs the SLAM libraries (cblox_tracking, cblox_drivers)\n");
    status = 2;
#endif
  }
  if (status != 0) return status;
  printTables(rows, o);
  bool ok = !rows.empty();
  for (const Row& r : rows) ok = ok && r.worst_difference < 1e-6;
  std::printf("\nall methods agree (max relative Frobenius difference < 1e-6): %s\n",
              ok ? "yes" : "NO");
  return ok ? 0 : 1;
}
