// The tracker's covariance service on a real sparse map: the first 250 frames of the
// simulated room loop, tracked and mapped by the SLAM system. All three solvers give the same
// Sigma_{i|j} (1e-9 relative); a keyframe is more certain given its neighbour than given a
// keyframe far away; bad pairs get their own error; the service thread answers every
// request exactly once, the ones pushed out of its queue with an error; a kept
// linearization answers later requests as a fresh one would, until the map changes.

#include "core/tracking/keyframe_covariance_service.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <limits>
#include <map>
#include <memory>
#include <mutex>
#include <shared_mutex>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include <gtest/gtest.h>
#include <Eigen/Eigenvalues>

#include "core/covariance/reduced_camera_matrix.h"
#include "core/optimization/ba_linearization.h"
#include "core/tracking/map_ba_problem.h"
#include "core/tracking/slam_system.h"
#include "drivers/open_frame_source.h"

namespace cblox {
namespace {

class KeyframeCovarianceServiceTest : public ::testing::Test {
 public:
  static void SetUpTestSuite() {
    std::string error;
    vocabulary_ = new BinaryVocabulary(*BinaryVocabulary::load(CBLOX_DEFAULT_VOCABULARY, &error));
    SourceConfig options;
    options.trajectory = "loop";
    options.max_frames = 250;
    std::unique_ptr<FrameSource> source = openFrameSource("sim:room", options, &error);
    ASSERT_NE(source, nullptr) << error;
    const RectifiedStereoCalibration& calibration = *source->info().stereo;
    camera_ =
        new TrackingCamera(makeTrackingCamera(calibration.intrinsics, calibration.baseline_m));
    slam_ = new SlamSystem(*camera_, SlamSystemConfig{}, vocabulary_);
    CaptureFrame frame;
    while (source->next(&frame, &error) == FrameSource::Status::kFrame) {
      slam_->trackStereo(static_cast<uint64_t>(frame.frame_id), frame.timestamp_ns, frame.left,
                         frame.right, frame.T_G_C->inverse());
    }
    slam_->waitUntilIdle();
    slam_->stop();  // the map stays as it is from here on
  }
  static void TearDownTestSuite() {
    delete slam_;
    delete camera_;
    delete vocabulary_;
  }

  static std::vector<uint64_t> keyframeIds() {
    std::vector<uint64_t> ids;
    for (const Keyframe* k : slam_->map().keyframes()) ids.push_back(k->id);
    std::sort(ids.begin(), ids.end());
    return ids;
  }
  static KeyframeCovarianceReply computeWith(CovarianceMethod method,
                                             const KeyframeCovarianceRequest& request) {
    KeyframeCovarianceServiceConfig config;
    config.method = method;
    KeyframeCovarianceService service(slam_->map(), *camera_, slam_->pyramid(), config, nullptr);
    return service.compute(request);
  }

  static BinaryVocabulary* vocabulary_;
  static TrackingCamera* camera_;
  static SlamSystem* slam_;
};
BinaryVocabulary* KeyframeCovarianceServiceTest::vocabulary_ = nullptr;
TrackingCamera* KeyframeCovarianceServiceTest::camera_ = nullptr;
SlamSystem* KeyframeCovarianceServiceTest::slam_ = nullptr;

double relativeDifference(const Eigen::Matrix<double, 6, 6>& a,
                          const Eigen::Matrix<double, 6, 6>& b) {
  return (a - b).norm() / b.norm();
}

void SolversAgreeAndNeighboursAreMoreCertainThanFarKeyframes() {
  using T = KeyframeCovarianceServiceTest;
  const std::vector<uint64_t> ids = T::keyframeIds();
  ASSERT_GE(ids.size(), 8u);
  const uint64_t last = ids.back(), before_last = ids[ids.size() - 2], second = ids[1];
  KeyframeCovarianceRequest request;
  request.request_id = 7;
  request.pairs = {{last, before_last}, {last, second}, {second, last}, {ids[3], ids[4]}};
  const KeyframeCovarianceReply batch = T::computeWith(CovarianceMethod::kBatch, request);
  const KeyframeCovarianceReply per_pair =
      T::computeWith(CovarianceMethod::kConstrainedOrdering, request);
  const KeyframeCovarianceReply kaess = T::computeWith(CovarianceMethod::kKaessRecovery, request);
  const KeyframeCovarianceReply sparse = T::computeWith(CovarianceMethod::kSparseSolve, request);
  EXPECT_EQ(batch.request_id, 7);
  EXPECT_EQ(batch.keyframes, static_cast<int>(ids.size()) - 1);  // the gauge has no block
  EXPECT_GT(batch.landmarks, 500);
  std::printf(
      "[ measured ] %d keyframes, %d landmarks: build %.1f ms; solve batch %.2f ms, "
      "per pair %.2f ms, Kaess %.2f ms for %zu pairs\n",
      batch.keyframes, batch.landmarks, batch.build_ms, batch.solve_ms, per_pair.solve_ms,
      kaess.solve_ms, request.pairs.size());
  ASSERT_EQ(batch.results.size(), request.pairs.size());
  for (size_t k = 0; k < request.pairs.size(); ++k) {
    const ConditionalCovariance& r = batch.results[k];
    ASSERT_TRUE(r.ok) << r.error;
    ASSERT_TRUE(per_pair.results[k].ok) << per_pair.results[k].error;
    ASSERT_TRUE(kaess.results[k].ok) << kaess.results[k].error;
    EXPECT_EQ(r.i, request.pairs[k].i);
    EXPECT_EQ(r.j, request.pairs[k].j);
    EXPECT_LT(relativeDifference(per_pair.results[k].sigma, r.sigma), 1e-9);
    EXPECT_LT(relativeDifference(kaess.results[k].sigma, r.sigma), 1e-9);
    ASSERT_TRUE(sparse.results[k].ok) << sparse.results[k].error;
    EXPECT_LT(relativeDifference(sparse.results[k].sigma, r.sigma), 1e-9);
    // Symmetric positive definite, q = 1 / lambda_max.
    EXPECT_LT((r.sigma - r.sigma.transpose()).norm(), 1e-12 * r.sigma.norm());
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 6, 6>> eigen(r.sigma);
    EXPECT_GT(eigen.eigenvalues().minCoeff(), 0.0);
    EXPECT_NEAR(r.q, 1.0 / eigen.eigenvalues().maxCoeff(), 1e-9 * r.q);
    std::printf("[ measured ] Sigma_{%llu|%llu}: sd %.2f mm / %.3f deg (largest), q %.3g\n",
                static_cast<unsigned long long>(r.i), static_cast<unsigned long long>(r.j),
                1e3 * std::sqrt(r.sigma.topLeftCorner<3, 3>().diagonal().maxCoeff()),
                std::sqrt(r.sigma.bottomRightCorner<3, 3>().diagonal().maxCoeff()) * 180 / M_PI,
                r.q);
  }
  // The last keyframe given its neighbour is more certain than given the second keyframe,
  // half a room away.
  EXPECT_GT(batch.results[0].q, 2.0 * batch.results[1].q);
}

void BadPairsGetTheirOwnErrors() {
  using T = KeyframeCovarianceServiceTest;
  const std::vector<uint64_t> ids = T::keyframeIds();
  KeyframeCovarianceRequest request;
  request.pairs = {{ids[2], ids[2]}, {999999, ids[1]}, {ids[0], ids[2]}, {ids[2], ids[1]}};
  for (const CovarianceMethod method :
       {CovarianceMethod::kBatch, CovarianceMethod::kConstrainedOrdering,
        CovarianceMethod::kKaessRecovery, CovarianceMethod::kSparseSolve}) {
    const KeyframeCovarianceReply reply = T::computeWith(method, request);
    ASSERT_EQ(reply.results.size(), 4u);
    EXPECT_FALSE(reply.results[0].ok);
    EXPECT_NE(reply.results[0].error.find("same keyframe"), std::string::npos)
        << reply.results[0].error;
    EXPECT_FALSE(reply.results[1].ok);
    EXPECT_NE(reply.results[1].error.find("999999"), std::string::npos) << reply.results[1].error;
    // ids[0] is the gauge: held fixed, it has no block (as i; as j see below).
    EXPECT_FALSE(reply.results[2].ok);
    EXPECT_NE(reply.results[2].error.find("not in the BA linearization"), std::string::npos)
        << reply.results[2].error;
    EXPECT_TRUE(reply.results[3].ok)
        << covarianceMethodName(method) << ": " << reply.results[3].error;
  }
}

// Given the gauge keyframe (held fixed by the BA) a keyframe's covariance is its marginal,
// [S^-1]_ii: checked against the dense inverse of the same S, for every method.
void GivenTheGaugeKeyframeTheAnswerIsTheMarginal() {
  using T = KeyframeCovarianceServiceTest;
  const std::vector<uint64_t> ids = T::keyframeIds();
  const MapBaProblem map_problem =
      buildMapBaProblem(T::slam_->map(), *T::camera_, T::slam_->pyramid(), nullptr);
  const ReducedCameraMatrix S = reduceCameraMatrix(linearizeBundleAdjustment(
      map_problem.problem, {}, KeyframeCovarianceServiceConfig{}.linearization));
  const Eigen::MatrixXd inverse = Eigen::MatrixXd(S.matrix).inverse();
  KeyframeCovarianceRequest request;
  request.pairs = {{ids[5], ids[0]}, {ids.back(), ids[0]}, {ids[5], ids[4]}};
  for (const CovarianceMethod method :
       {CovarianceMethod::kBatch, CovarianceMethod::kConstrainedOrdering,
        CovarianceMethod::kKaessRecovery, CovarianceMethod::kSparseSolve}) {
    const KeyframeCovarianceReply reply = T::computeWith(method, request);
    ASSERT_EQ(reply.results.size(), 3u);
    for (size_t k = 0; k < 2; ++k) {
      const ConditionalCovariance& r = reply.results[k];
      ASSERT_TRUE(r.ok) << r.error;
      const int b = S.blockOf(request.pairs[k].i);
      ASSERT_GE(b, 0);
      const Eigen::Matrix<double, 6, 6> expected = inverse.block<6, 6>(6 * b, 6 * b);
      EXPECT_LT(relativeDifference(r.sigma, expected), 1e-9) << covarianceMethodName(method);
    }
    // Conditioning on a neighbour as well can only shrink it.
    ASSERT_TRUE(reply.results[2].ok) << reply.results[2].error;
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 6, 6>> shrink(reply.results[0].sigma -
                                                                            reply.results[2].sigma);
    EXPECT_GT(shrink.eigenvalues().minCoeff(), -1e-12 * reply.results[0].sigma.norm());
  }
}

void TheThreadAnswersEveryRequestOnceAndDropsTheOldest() {
  using T = KeyframeCovarianceServiceTest;
  const std::vector<uint64_t> ids = T::keyframeIds();
  std::mutex mutex;
  std::map<int64_t, KeyframeCovarianceReply> replies;
  std::atomic<int> duplicates{0};
  KeyframeCovarianceServiceConfig config;
  config.max_queued_requests = 1;
  KeyframeCovarianceService service(T::slam_->map(), *T::camera_, T::slam_->pyramid(), config,
                                    [&](const KeyframeCovarianceReply& r) {
                                      std::lock_guard<std::mutex> lock(mutex);
                                      if (!replies.emplace(r.request_id, r).second) ++duplicates;
                                    });
  // Queued before the thread runs: with room for one, requests 1..4 are pushed out at once.
  for (int64_t id = 1; id <= 5; ++id) {
    service.submit({id, {{ids[3], ids[2]}}});
  }
  {
    std::lock_guard<std::mutex> lock(mutex);
    ASSERT_EQ(replies.size(), 4u);
    for (int64_t id = 1; id <= 4; ++id) {
      ASSERT_FALSE(replies.at(id).results.at(0).ok);
      EXPECT_NE(replies.at(id).results[0].error.find("busy"), std::string::npos);
    }
  }
  service.start();
  for (int i = 0; i < 2000; ++i) {
    {
      std::lock_guard<std::mutex> lock(mutex);
      if (replies.size() == 5) break;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  service.stop();
  std::lock_guard<std::mutex> lock(mutex);
  ASSERT_EQ(replies.size(), 5u);
  EXPECT_TRUE(replies.at(5).results.at(0).ok) << replies.at(5).results[0].error;
  EXPECT_EQ(duplicates.load(), 0);
  const KeyframeCovarianceServiceStats stats = service.stats();
  EXPECT_EQ(stats.requests, 5u);
  EXPECT_EQ(stats.answered, 5u);
  EXPECT_EQ(stats.dropped, 4u);
  EXPECT_EQ(stats.pairs_ok, 1u);
  EXPECT_EQ(stats.pairs_failed, 4u);
}

// A linearization answers later requests while it is young enough, the map has not changed
// index (loop closure, global BA) and it has every keyframe asked about; its answers are
// those of a fresh linearization of the same (here unchanging) map.
void AKeptLinearizationAnswersLaterRequests() {
  using T = KeyframeCovarianceServiceTest;
  const std::vector<uint64_t> ids = T::keyframeIds();
  std::mutex mutex;
  std::condition_variable cv;
  std::vector<KeyframeCovarianceReply> replies;
  KeyframeCovarianceServiceConfig config;
  config.method = CovarianceMethod::kSparseSolve;  // factorises once: reused too
  config.max_linearization_age_s = 600.0;
  config.min_linearization_interval_s = 0.0;  // every rebuild at once
  KeyframeCovarianceService service(T::slam_->map(), *T::camera_, T::slam_->pyramid(), config,
                                    [&](const KeyframeCovarianceReply& r) {
                                      std::lock_guard<std::mutex> lock(mutex);
                                      replies.push_back(r);
                                      cv.notify_all();
                                    });
  service.start();
  const auto ask = [&](KeyframeCovarianceRequest request) {
    size_t n = 0;
    {
      std::lock_guard<std::mutex> lock(mutex);
      n = replies.size() + 1;
    }
    service.submit(request);
    std::unique_lock<std::mutex> lock(mutex);
    EXPECT_TRUE(cv.wait_for(lock, std::chrono::seconds(60), [&] { return replies.size() >= n; }));
    return replies.back();
  };
  const KeyframeCovarianceRequest first{1, {{ids[3], ids[2]}}};
  const KeyframeCovarianceRequest second{2, {{ids[6], ids[5]}, {ids[5], ids[0]}}};
  const KeyframeCovarianceReply a = ask(first);
  EXPECT_FALSE(a.reused);
  EXPECT_GT(a.build_ms, 0.0);
  const KeyframeCovarianceReply b = ask(second);
  EXPECT_TRUE(b.reused);
  EXPECT_EQ(b.build_ms, 0.0);
  EXPECT_GE(b.linearization_age_ms, a.linearization_age_ms);
  const KeyframeCovarianceReply fresh = service.compute(second);
  ASSERT_EQ(b.results.size(), 2u);
  for (size_t k = 0; k < 2; ++k) {
    ASSERT_TRUE(b.results[k].ok) << b.results[k].error;
    EXPECT_LT(relativeDifference(b.results[k].sigma, fresh.results[k].sigma), 1e-12);
  }
  // A loop closure (or global BA) bumps the map's change index: linearised again.
  {
    // What the loop closer does (the SLAM system, stopped, exposes its map read-only).
    SparseMap& map = const_cast<SparseMap&>(T::slam_->map());
    std::unique_lock<std::shared_mutex> lock(map.mutex());
    map.bumpChangeIndex();
  }
  EXPECT_FALSE(ask(first).reused);
  EXPECT_TRUE(ask(first).reused);
  // A keyframe the kept linearization has no block for: linearised again (it may be new).
  const KeyframeCovarianceReply unknown = ask({5, {{999999, ids[1]}}});
  EXPECT_FALSE(unknown.reused);
  ASSERT_EQ(unknown.results.size(), 1u);
  EXPECT_FALSE(unknown.results[0].ok);
  // A keyframe culled since: the kept linearization still has its block (a culled keyframe
  // is tied to its parent for good, so that block is still its answer).
  EXPECT_TRUE(ask(first).reused);
  {
    SparseMap& map = const_cast<SparseMap&>(T::slam_->map());
    std::unique_lock<std::shared_mutex> lock(map.mutex());
    map.cullKeyframe(map.keyframe(static_cast<KeyframeId>(ids[3])));
    ASSERT_TRUE(map.keyframe(static_cast<KeyframeId>(ids[3]))->bad());
  }
  const KeyframeCovarianceReply culled = ask(first);
  EXPECT_TRUE(culled.reused);
  ASSERT_EQ(culled.results.size(), 1u);
  EXPECT_TRUE(culled.results[0].ok) << culled.results[0].error;
  // Linearised afresh (after a loop closure), it has no block for the culled keyframe and
  // answers through its parent.
  {
    SparseMap& map = const_cast<SparseMap&>(T::slam_->map());
    std::unique_lock<std::shared_mutex> lock(map.mutex());
    map.bumpChangeIndex();
  }
  const KeyframeCovarianceReply through_parent = ask(first);
  EXPECT_FALSE(through_parent.reused);
  ASSERT_EQ(through_parent.results.size(), 1u);
  EXPECT_TRUE(through_parent.results[0].ok) << through_parent.results[0].error;
  EXPECT_GT(through_parent.results[0].q, 0.0);
  service.stop();
  const KeyframeCovarianceServiceStats stats = service.stats();
  EXPECT_EQ(stats.linearizations, 4u);
  EXPECT_EQ(stats.reused, 4u);

  // Age 0: every request is linearised afresh.
  config.max_linearization_age_s = 0.0;
  std::atomic<int> strict_replies{0};
  KeyframeCovarianceService strict(T::slam_->map(), *T::camera_, T::slam_->pyramid(), config,
                                   [&](const KeyframeCovarianceReply& r) {
                                     EXPECT_FALSE(r.reused);
                                     ++strict_replies;
                                   });
  strict.start();
  strict.submit(second);
  strict.submit(second);
  for (int i = 0; i < 6000 && strict_replies.load() < 2; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  strict.stop();
  EXPECT_EQ(strict_replies.load(), 2);
  EXPECT_EQ(strict.stats().linearizations, 2u);
  EXPECT_EQ(strict.stats().reused, 0u);
}

// A fresh linearization starts no sooner than min_linearization_interval_s after the last
// one started: with a fresh one per request (age 0) three requests take at least two
// intervals, the two later ones counted as delayed. stop() during such a wait answers the
// waiting request with an error at once.
void FreshLinearizationsAreSpacedByTheInterval() {
  using T = KeyframeCovarianceServiceTest;
  const std::vector<uint64_t> ids = T::keyframeIds();
  std::mutex mutex;
  std::condition_variable cv;
  std::vector<KeyframeCovarianceReply> replies;
  const auto collect = [&](const KeyframeCovarianceReply& r) {
    std::lock_guard<std::mutex> lock(mutex);
    replies.push_back(r);
    cv.notify_all();
  };
  const auto waitFor = [&](size_t n, std::chrono::seconds limit) {
    std::unique_lock<std::mutex> lock(mutex);
    return cv.wait_for(lock, limit, [&] { return replies.size() >= n; });
  };
  KeyframeCovarianceServiceConfig config;
  config.max_linearization_age_s = 0.0;
  config.min_linearization_interval_s = 1.0;
  {
    KeyframeCovarianceService service(T::slam_->map(), *T::camera_, T::slam_->pyramid(), config,
                                      collect);
    service.start();
    const auto start = std::chrono::steady_clock::now();
    for (int64_t id = 1; id <= 3; ++id) service.submit({id, {{ids[3], ids[2]}}});
    ASSERT_TRUE(waitFor(3, std::chrono::seconds(60)));
    const double elapsed_s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    service.stop();
    EXPECT_GE(elapsed_s, 2.0);
    const KeyframeCovarianceServiceStats stats = service.stats();
    EXPECT_EQ(stats.linearizations, 3u);
    EXPECT_EQ(stats.linearizations_delayed, 2u);
    EXPECT_GT(stats.delayed_ms, 1000.0);
    for (const KeyframeCovarianceReply& r : replies) {
      ASSERT_EQ(r.results.size(), 1u);
      EXPECT_TRUE(r.results[0].ok) << r.results[0].error;
    }
  }
  replies.clear();
  config.min_linearization_interval_s = 600.0;
  KeyframeCovarianceService waiting(T::slam_->map(), *T::camera_, T::slam_->pyramid(), config,
                                    collect);
  waiting.start();
  waiting.submit({1, {{ids[3], ids[2]}}});
  ASSERT_TRUE(waitFor(1, std::chrono::seconds(60)));
  waiting.submit({2, {{ids[3], ids[2]}}});
  std::this_thread::sleep_for(std::chrono::milliseconds(100));  // now waiting for its slot
  const auto stop_start = std::chrono::steady_clock::now();
  waiting.stop();
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - stop_start).count(),
            5.0);
  std::lock_guard<std::mutex> lock(mutex);
  ASSERT_EQ(replies.size(), 2u);
  EXPECT_EQ(replies[1].request_id, 2);
  ASSERT_EQ(replies[1].results.size(), 1u);
  EXPECT_FALSE(replies[1].results[0].ok);
  EXPECT_NE(replies[1].results[0].error.find("stopping"), std::string::npos);
  EXPECT_EQ(waiting.stats().answered, 2u);
}

// A culled keyframe K is answered through its parent P (to which it is tied by
// T_parent_this): Sigma_{K|J} = J_KP Sigma_{P|J} J_KP^T, with the Jacobian J_KP of K's
// left-perturbation tangent with respect to P's taken here by central differences of exp and
// log (independent of Transformationd::adjoint); given a culled J the answer is the answer
// given its parent; two keyframes tied together: ok, sigma 0, q the largest double.
void CulledKeyframesAreAnsweredThroughTheirParent() {
  using T = KeyframeCovarianceServiceTest;
  SparseMap& map = const_cast<SparseMap&>(T::slam_->map());
  const std::vector<uint64_t> ids = T::keyframeIds();
  ASSERT_GE(ids.size(), 10u);
  uint64_t k_id = 0, p_id = 0;
  Transformationd T_P_K;
  {
    std::unique_lock<std::shared_mutex> lock(map.mutex());
    for (size_t n = ids.size() / 2; n + 2 < ids.size() && k_id == 0; ++n) {
      Keyframe* k = map.keyframe(static_cast<KeyframeId>(ids[n]));
      if (k->parent() == nullptr || k->parent()->id == 0) continue;
      map.cullKeyframe(k);
      if (!k->bad()) continue;  // a loop keyframe is kept
      k_id = ids[n];
      p_id = static_cast<uint64_t>(k->parent()->id);
      T_P_K = k->T_parent_this();
    }
  }
  ASSERT_NE(k_id, 0u) << "no keyframe could be culled";
  const uint64_t j_id = ids.back() == p_id ? ids[ids.size() - 2] : ids.back();
  const uint64_t gauge = ids[0];
  KeyframeCovarianceRequest request;
  request.pairs = {{k_id, j_id}, {p_id, j_id}, {j_id, k_id},  {j_id, p_id},
                   {k_id, p_id}, {p_id, k_id}, {k_id, gauge}, {p_id, gauge}};

  // d(delta_K)/d(delta_P) for T_K_G = T_K_P * T_P_G, left perturbations of T_C_G.
  const Transformationd T_K_P = T_P_K.inverse();
  const Transformationd T_P_G = map.keyframe(static_cast<KeyframeId>(p_id))->T_C_G();
  const Transformationd T_K_G = T_K_P * T_P_G;
  Eigen::Matrix<double, 6, 6> jacobian;
  const double h = 1e-6;
  for (int m = 0; m < 6; ++m) {
    Transformationd::Vec6 e = Transformationd::Vec6::Zero();
    e[m] = h;
    const auto tangent = [&](double sign) {
      return (T_K_P * Transformationd::exp(sign * e) * T_P_G * T_K_G.inverse()).log();
    };
    jacobian.col(m) = (tangent(1.0) - tangent(-1.0)) / (2.0 * h);
  }

  for (const CovarianceMethod method : {CovarianceMethod::kSparseSolve, CovarianceMethod::kBatch}) {
    SCOPED_TRACE(covarianceMethodName(method));
    const KeyframeCovarianceReply reply = T::computeWith(method, request);
    ASSERT_EQ(reply.results.size(), request.pairs.size());
    for (const ConditionalCovariance& r : reply.results) ASSERT_TRUE(r.ok) << r.error;
    for (const auto& [culled, parent] : {std::pair<size_t, size_t>{0, 1}, {6, 7}}) {
      const ConditionalCovariance& r = reply.results[culled];
      EXPECT_EQ(r.i, k_id);
      const Eigen::Matrix<double, 6, 6> expected =
          jacobian * reply.results[parent].sigma * jacobian.transpose();
      EXPECT_LT(relativeDifference(r.sigma, expected), 1e-6);
      const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 6, 6>> eigen(r.sigma);
      EXPECT_NEAR(r.q, 1.0 / eigen.eigenvalues().maxCoeff(), 1e-9 * r.q);
    }
    // Given the culled keyframe: exactly the answer given its parent.
    EXPECT_EQ(reply.results[2].j, k_id);
    EXPECT_EQ(reply.results[2].sigma, reply.results[3].sigma);
    EXPECT_EQ(reply.results[2].q, reply.results[3].q);
    for (const size_t tied : {4, 5}) {
      EXPECT_EQ(reply.results[tied].sigma, (Eigen::Matrix<double, 6, 6>::Zero()));
      EXPECT_EQ(reply.results[tied].q, std::numeric_limits<double>::max());
    }
  }
}

// One ctest case (the fixture's SLAM run takes most of the time; ctest runs every case in
// a process of its own).
TEST_F(KeyframeCovarianceServiceTest, AnswersFromTheLiveRoomMap) {
  {
    SCOPED_TRACE("solvers agree, neighbours more certain");
    SolversAgreeAndNeighboursAreMoreCertainThanFarKeyframes();
  }
  {
    SCOPED_TRACE("bad pairs");
    BadPairsGetTheirOwnErrors();
  }
  {
    SCOPED_TRACE("given the gauge: the marginal");
    GivenTheGaugeKeyframeTheAnswerIsTheMarginal();
  }
  {
    SCOPED_TRACE("the service thread");
    TheThreadAnswersEveryRequestOnceAndDropsTheOldest();
  }
  {
    SCOPED_TRACE("a kept linearization");
    AKeptLinearizationAnswersLaterRequests();
  }
  {
    SCOPED_TRACE("the interval between linearizations");
    FreshLinearizationsAreSpacedByTheInterval();
  }
  {
    SCOPED_TRACE("culled keyframes");
    CulledKeyframesAreAnsweredThroughTheirParent();
  }
}

TEST(KeyframeCovarianceServiceConfigTest, BadValuesAreNamed) {
  KeyframeCovarianceServiceConfig config;
  EXPECT_EQ(config.validate(), "");
  config.max_queued_requests = 0;
  EXPECT_NE(config.validate().find("max_queued_requests"), std::string::npos);
  config = KeyframeCovarianceServiceConfig{};
  config.niceness = 20;
  EXPECT_NE(config.validate().find("niceness"), std::string::npos);
  config = KeyframeCovarianceServiceConfig{};
  config.max_linearization_age_s = -1.0;
  EXPECT_NE(config.validate().find("max_linearization_age_s"), std::string::npos);
  config = KeyframeCovarianceServiceConfig{};
  config.min_linearization_interval_s = std::numeric_limits<double>::infinity();
  EXPECT_NE(config.validate().find("min_linearization_interval_s"), std::string::npos);
  config = KeyframeCovarianceServiceConfig{};
  config.reduction.landmark_min_relative_eigenvalue = 1.0;
  EXPECT_NE(config.validate().find("reduction."), std::string::npos);
}

}  // namespace
}  // namespace cblox
