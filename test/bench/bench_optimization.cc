// Google Benchmark: the sparse SLAM's optimisers (core/optimization), single-threaded.
//  - motion-only pose optimisation (hand-written LM, ORB-SLAM2's 4 x 10 scheme) with 300
//    observations (1 px noise, 10% gross outliers);
//  - local BA of an ORB-SLAM2-like window: 10 free + 10 fixed keyframes, 2000 landmarks,
//    ~8000 observations (1 px noise, 2% gross outliers), with Ceres' DENSE_SCHUR and
//    SPARSE_SCHUR and with our own Schur LM (schur_lm.h; NATIVE_DENSE_SCHUR);
//  - a window of the town's median local BA size (33 free + 55 fixed keyframes, 2400
//    landmarks, ~13,000 observations), Ceres' DENSE_SCHUR against ours;
//  - BA with 10 / 60 / 120 / 250 free keyframes and four solvers (kAuto's crossovers);
//  - global BA (globalBundleAdjustmentConfig: 10 robust iterations) of closed two-lap loops
//    of 500 and 1000 keyframes (test/covariance/loop_scene.h: 50 landmarks per keyframe,
//    3-8 observers, 30 % seen again on the other lap; 1 px noise, 1 % gross outliers),
//    Ceres' SPARSE_SCHUR against ours with the sparse reduced matrix (NATIVE_SPARSE_SCHUR);
//  - the BA linearization + information matrix of the local window (for core/covariance);
//  - an SE(3) pose graph of 500 keyframes (loop with covisibility edges and drift).
//
//   build/test/bench/cblox-bench-optimization --benchmark_repetitions=3
//       --benchmark_report_aggregates_only=true   (one command line)

#include <benchmark/benchmark.h>

#include <algorithm>
#include <random>
#include <vector>

#include "core/optimization/ba_linearization.h"
#include "core/optimization/bundle_adjustment.h"
#include "core/optimization/pose_graph_optimizer.h"
#include "core/optimization/pose_optimizer.h"
#include "test/covariance/loop_scene.h"
#include "test/optimization/synthetic_scenes.h"

namespace cblox {
namespace {

struct PoseWorkload {
  test::PoseScene scene;
  Transformationd start;
};

const PoseWorkload& poseWorkload() {
  static const PoseWorkload w = [] {
    PoseWorkload result;
    result.scene = test::makePoseScene(300, 1.0, 7);
    std::mt19937 rng(8);
    for (size_t i = 0; i < result.scene.observations.size(); i += 10) {
      result.scene.observations[i].u += 40.0;
    }
    result.start = test::perturbPose(result.scene.T_C_G_true, 0.03, 0.02, rng);
    return result;
  }();
  return w;
}

void BM_PoseOptimization(benchmark::State& state) {
  const PoseWorkload& w = poseWorkload();
  const StereoCameraModel camera = test::syntheticCamera();
  PoseOptimizationResult result;
  for (auto _ : state) {
    result = optimizePose(camera, w.start, w.scene.observations);
    benchmark::DoNotOptimize(result);
  }
  state.counters["observations"] = static_cast<double>(w.scene.observations.size());
  state.counters["inliers"] = result.num_inliers;
  state.counters["iterations"] = result.iterations;
}

// A window of `keyframes` keyframes (the first `fixed` fixed) over 2000 landmarks, about 4
// observations per landmark.
test::BaScene window(int keyframes, int fixed, double observe_probability,
                     int landmarks = 2000) {
  test::BaSceneOptions options;
  options.keyframes = keyframes;
  options.landmarks = landmarks;
  options.step_m = 0.25;
  options.observe_probability = observe_probability;
  options.pixel_noise = 1.0;
  options.seed = 11;
  test::BaScene scene = test::makeBaScene(options);
  for (int k = 0; k < fixed; ++k) scene.problem.keyframes[k].fixed = true;
  for (size_t i = 0; i < scene.problem.observations.size(); i += 50) {
    scene.problem.observations[i].v += 30.0;  // 2% gross outliers
  }
  test::perturbInitialState(&scene, 0.02, 0.01, 0.05, 12);
  return scene;
}

const test::BaScene& localWindow() {
  static const test::BaScene scene = window(20, 10, 0.225);
  return scene;
}

const test::BaScene& townWindow() {
  static const test::BaScene scene = window(88, 55, 0.125, 2400);
  return scene;
}

// The solver argument of the BA benchmarks: 0 Ceres' DENSE_SCHUR, 1 Ceres' SPARSE_SCHUR, 2 ours
// with a dense reduced matrix, 3 ours with a sparse one.
BaLinearSolver solverOf(int64_t arg) {
  switch (arg) {
    case 0:
      return BaLinearSolver::kDenseSchur;
    case 1:
      return BaLinearSolver::kSparseSchur;
    case 2:
      return BaLinearSolver::kNativeDenseSchur;
    default:
      return BaLinearSolver::kNativeSparseSchur;
  }
}

void runBundleAdjustment(benchmark::State& state, const test::BaScene& scene,
                         BaLinearSolver solver, BundleAdjustmentConfig config = {}) {
  config.linear_solver = solver;
  BundleAdjustmentResult result;
  for (auto _ : state) {
    result = bundleAdjust(scene.problem, config);
    benchmark::DoNotOptimize(result);
  }
  int free_keyframes = 0;
  for (const BaKeyframe& kf : scene.problem.keyframes) free_keyframes += kf.fixed ? 0 : 1;
  state.counters["free_kf"] = free_keyframes;
  state.counters["landmarks"] = static_cast<double>(scene.problem.landmarks.size());
  state.counters["observations"] = static_cast<double>(scene.problem.observations.size());
  state.counters["outliers"] = result.num_outliers;
  state.counters["iterations"] = result.iterations;
  state.SetLabel(result.linear_solver);
}

void BM_LocalBundleAdjustment(benchmark::State& state) {
  runBundleAdjustment(state, localWindow(), solverOf(state.range(0)));
}

void BM_TownBundleAdjustment(benchmark::State& state) {
  runBundleAdjustment(state, townWindow(), solverOf(state.range(0)));
}

// range(0) free keyframes (plus 10 fixed), range(1) the solver as above.
void BM_BundleAdjustmentSolvers(benchmark::State& state) {
  static std::vector<std::pair<int, test::BaScene>> scenes;
  const int free = static_cast<int>(state.range(0));
  auto it =
      std::find_if(scenes.begin(), scenes.end(), [&](const auto& s) { return s.first == free; });
  if (it == scenes.end()) {
    // Keep ~4 observations per landmark as the window grows.
    scenes.emplace_back(free, window(free + 10, 10, 0.225 * 20.0 / (free + 10)));
    it = scenes.end() - 1;
  }
  runBundleAdjustment(state, it->second, solverOf(state.range(1)));
}

// A closed two-lap loop of `keyframes` keyframes as global BA sees it after a loop closure:
// keyframe 0 fixed, noisy observations with gross outliers, the state perturbed.
test::BaScene globalLoop(int keyframes) {
  test::LoopSceneOptions options;
  options.keyframes = keyframes;
  options.seed = 31;
  test::BaScene scene = test::makeLoopBaScene(options);
  std::mt19937 rng(32);
  std::normal_distribution<double> pixel(0.0, 1.0);
  for (size_t i = 0; i < scene.problem.observations.size(); ++i) {
    BaObservation& o = scene.problem.observations[i];
    const double du = pixel(rng);
    o.u += du;
    o.v += pixel(rng);
    if (o.u_right >= 0.0) o.u_right += du + 0.5 * pixel(rng);
    if (i % 100 == 0) o.v += 30.0;  // 1 % gross outliers
  }
  test::perturbInitialState(&scene, 0.02, 0.005, 0.03, 33);
  return scene;
}

// range(0) keyframes, range(1) the solver as above.
void BM_GlobalBundleAdjustment(benchmark::State& state) {
  static std::vector<std::pair<int, test::BaScene>> scenes;
  const int keyframes = static_cast<int>(state.range(0));
  auto it = std::find_if(scenes.begin(), scenes.end(),
                         [&](const auto& s) { return s.first == keyframes; });
  if (it == scenes.end()) {
    scenes.emplace_back(keyframes, globalLoop(keyframes));
    it = scenes.end() - 1;
  }
  runBundleAdjustment(state, it->second, solverOf(state.range(1)), globalBundleAdjustmentConfig());
}

void BM_LinearizationAndInformation(benchmark::State& state) {
  const test::BaScene& scene = localWindow();
  const BundleAdjustmentResult ba = bundleAdjust(scene.problem);
  for (auto _ : state) {
    const BaLinearization lin = linearizeBundleAdjustmentSolution(scene.problem, ba);
    const Eigen::SparseMatrix<double> H = informationMatrix(lin);
    benchmark::DoNotOptimize(H.nonZeros());
  }
}

void BM_PoseGraph(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  std::vector<Transformationd> truth;
  for (int k = 0; k < n; ++k) {
    const double a = 2.0 * M_PI * k / n;
    truth.push_back(Transformationd::exp((Eigen::Matrix<double, 6, 1>() << 20.0 * std::cos(a), 0.0,
                                          20.0 * std::sin(a), 0.0, -a, 0.0)
                                             .finished())
                        .inverse());
  }
  std::vector<PoseGraphEdge> edges;
  for (int k = 0; k < n; ++k) {
    for (int d = 1; d <= 3; ++d) {  // spanning tree + covisibility edges; the last wrap = loop
      if (k + d >= n && !(d == 1 && k == n - 1)) continue;
      PoseGraphEdge e;
      e.i = k;
      e.j = (k + d) % n;
      e.T_i_j = truth[e.i] * truth[e.j].inverse();
      edges.push_back(e);
    }
  }
  std::mt19937 rng(21);
  std::vector<PoseGraphVertex> vertices;
  Transformationd T = truth[0];
  for (int k = 0; k < n; ++k) {
    vertices.push_back(PoseGraphVertex{static_cast<std::uint64_t>(k), T, k == 0});
    T = test::perturbPose(truth[(k + 1) % n] * truth[k].inverse(), 0.01, 0.002, rng) * T;
  }
  PoseGraphResult result;
  for (auto _ : state) {
    result = optimizePoseGraph(vertices, edges);
    benchmark::DoNotOptimize(result);
  }
  state.counters["edges"] = static_cast<double>(edges.size());
  state.counters["iterations"] = result.iterations;
}

BENCHMARK(BM_PoseOptimization)->Name("pose_optimization/300_obs")->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_LocalBundleAdjustment)
    ->Name("local_ba/10_free_10_fixed")
    ->ArgName("solver")
    ->DenseRange(0, 2)
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_TownBundleAdjustment)
    ->Name("local_ba/town_33_free_55_fixed")
    ->ArgName("solver")
    ->Arg(0)
    ->Arg(2)
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_BundleAdjustmentSolvers)
    ->Name("ba_solvers")
    ->ArgNames({"free_kf", "solver"})
    ->ArgsProduct({{10, 60, 120, 250}, {0, 1, 2, 3}})
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_GlobalBundleAdjustment)
    ->Name("global_ba/loop")
    ->ArgNames({"keyframes", "solver"})
    ->ArgsProduct({{500, 1000}, {1, 3}})
    ->Unit(benchmark::kMillisecond)
    ->Iterations(1);
BENCHMARK(BM_LinearizationAndInformation)
    ->Name("ba_linearization/local_window")
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_PoseGraph)->Name("pose_graph/keyframes")->Arg(500)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace cblox

BENCHMARK_MAIN();
