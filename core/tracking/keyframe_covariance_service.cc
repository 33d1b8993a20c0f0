#include "core/tracking/keyframe_covariance_service.h"

#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <chrono>
#include <memory>
#include <optional>
#include <stdexcept>
#include <utility>

#include "core/covariance/batch_covariance_solver.h"
#include "core/covariance/constrained_ordering_solver.h"
#include "core/covariance/kaess_recovery_solver.h"
#include "core/covariance/sparse_solve_solver.h"
#include "core/tracking/map_ba_problem.h"

namespace cblox {

const char* covarianceMethodName(CovarianceMethod method) {
  switch (method) {
    case CovarianceMethod::kConstrainedOrdering:
      return "constrained_ordering";
    case CovarianceMethod::kBatch:
      return "batch";
    case CovarianceMethod::kKaessRecovery:
      return "kaess_recovery";
    case CovarianceMethod::kSparseSolve:
      return "sparse_solve";
  }
  return "?";
}

std::string KeyframeCovarianceServiceConfig::validate() const {
  if (max_queued_requests < 1) return "max_queued_requests must be >= 1";
  if (niceness < 0 || niceness > 19) {
    return "niceness must be in [0, 19], got " + std::to_string(niceness);
  }
  if (std::string e = cblox::validate(linearization); !e.empty()) return "linearization." + e;
  if (std::string e = cblox::validate(reduction); !e.empty()) return "reduction." + e;
  return {};
}

namespace {

double msSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
      .count();
}

std::unique_ptr<ConditionalCovarianceSolver> makeSolver(CovarianceMethod method,
                                                        ReducedCameraMatrix S) {
  switch (method) {
    case CovarianceMethod::kConstrainedOrdering:
      return std::make_unique<ConstrainedOrderingSolver>(std::move(S));
    case CovarianceMethod::kKaessRecovery:
      return std::make_unique<KaessRecoverySolver>(std::move(S));
    case CovarianceMethod::kSparseSolve:
      return std::make_unique<SparseSolveCovarianceSolver>(std::move(S));
    case CovarianceMethod::kBatch:
      break;
  }
  return std::make_unique<BatchCovarianceSolver>(std::move(S));
}

std::vector<ConditionalCovariance> failAll(std::span<const KeyframePair> pairs,
                                           const std::string& error) {
  std::vector<ConditionalCovariance> results;
  results.reserve(pairs.size());
  for (const KeyframePair& pair : pairs) results.push_back(failedPair(pair, error));
  return results;
}

}  // namespace

KeyframeCovarianceService::KeyframeCovarianceService(const SparseMap& map,
                                                     const TrackingCamera& camera,
                                                     const ScalePyramid& pyramid,
                                                     const KeyframeCovarianceServiceConfig& config,
                                                     ReplyCallback reply)
    : map_(map), camera_(camera), pyramid_(pyramid), config_(config), reply_(std::move(reply)) {
  if (const std::string e = config_.validate(); !e.empty()) {
    throw std::invalid_argument("KeyframeCovarianceServiceConfig: " + e);
  }
}

KeyframeCovarianceService::~KeyframeCovarianceService() { stop(); }

void KeyframeCovarianceService::start() {
  std::lock_guard<std::mutex> lock(mutex_);
  if (started_) return;
  started_ = true;
  thread_ = std::thread([this] { loop(); });
}

void KeyframeCovarianceService::stop() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!started_ || stop_) return;
    stop_ = true;
  }
  cv_.notify_all();
  thread_.join();
}

void KeyframeCovarianceService::submit(KeyframeCovarianceRequest request) {
  std::optional<KeyframeCovarianceRequest> dropped;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    ++stats_.requests;
    queue_.push_back(std::move(request));
    if (queue_.size() > config_.max_queued_requests) {
      dropped = std::move(queue_.front());
      queue_.pop_front();
      ++stats_.dropped;
      ++stats_.answered;
      stats_.pairs_failed += dropped->pairs.size();
    }
  }
  cv_.notify_all();
  if (dropped && reply_) {
    KeyframeCovarianceReply reply;
    reply.request_id = dropped->request_id;
    reply.results = failAll(dropped->pairs, "dropped: covariance service busy");
    reply_(reply);
  }
}

KeyframeCovarianceReply KeyframeCovarianceService::compute(
    const KeyframeCovarianceRequest& request) const {
  KeyframeCovarianceReply reply;
  reply.request_id = request.request_id;
  const auto start = std::chrono::steady_clock::now();
  std::unique_ptr<ConditionalCovarianceSolver> solver;
  // Pairs conditioned on the gauge keyframe are answered apart (it has no block in S).
  std::vector<size_t> gauge_pairs, other_pairs;
  std::vector<ConditionalCovariance> gauge_results;
  try {
    const MapBaProblem map_problem = buildMapBaProblem(map_, camera_, pyramid_, nullptr);
    reply.landmarks = static_cast<int>(map_problem.problem.landmarks.size());
    if (map_problem.problem.keyframes.size() < 2 || map_problem.problem.observations.empty()) {
      reply.results = failAll(request.pairs, "the map has fewer than two keyframes");
      return reply;
    }
    ReducedCameraMatrix S = reduceCameraMatrix(
        linearizeBundleAdjustment(map_problem.problem, {}, config_.linearization),
        config_.reduction);
    reply.keyframes = S.numBlocks();
    uint64_t gauge = 0;
    for (const BaKeyframe& k : map_problem.problem.keyframes) {
      if (k.fixed) gauge = k.id;
    }
    // Given the gauge g (held fixed, so S^-1 is already conditioned on it) the answer is
    // the marginal [S^-1]_ii.
    std::optional<ConstrainedOrderingSolver> marginals;
    for (size_t p = 0; p < request.pairs.size(); ++p) {
      const KeyframePair& pair = request.pairs[p];
      if (pair.j == gauge && pair.i != gauge) {
        if (!marginals) marginals.emplace(S);
        gauge_pairs.push_back(p);
        gauge_results.push_back(marginals->marginal(pair));
      } else {
        other_pairs.push_back(p);
      }
    }
    solver = makeSolver(config_.method, std::move(S));
  } catch (const std::exception& e) {
    reply.results = failAll(request.pairs, std::string("linearization failed: ") + e.what());
    return reply;
  }
  reply.build_ms = msSince(start);
  const auto solve_start = std::chrono::steady_clock::now();
  std::vector<KeyframePair> others;
  for (const size_t p : other_pairs) others.push_back(request.pairs[p]);
  const std::vector<ConditionalCovariance> other_results =
      others.empty() ? std::vector<ConditionalCovariance>{} : solver->compute(others);
  reply.results.resize(request.pairs.size());
  for (size_t k = 0; k < other_pairs.size(); ++k) reply.results[other_pairs[k]] = other_results[k];
  for (size_t k = 0; k < gauge_pairs.size(); ++k) reply.results[gauge_pairs[k]] = gauge_results[k];
  reply.solve_ms = msSince(solve_start);
  return reply;
}

void KeyframeCovarianceService::loop() {
  if (config_.niceness > 0) {
    const pid_t tid = static_cast<pid_t>(::syscall(SYS_gettid));
    ::setpriority(PRIO_PROCESS, static_cast<id_t>(tid), config_.niceness);  // best effort
  }
  std::unique_lock<std::mutex> lock(mutex_);
  while (true) {
    cv_.wait(lock, [this] { return stop_ || !queue_.empty(); });
    if (stop_) break;
    const KeyframeCovarianceRequest request = std::move(queue_.front());
    queue_.pop_front();
    lock.unlock();
    const KeyframeCovarianceReply reply = compute(request);
    lock.lock();
    ++stats_.answered;
    for (const ConditionalCovariance& r : reply.results)
      ++(r.ok ? stats_.pairs_ok : stats_.pairs_failed);
    stats_.last_build_ms = reply.build_ms;
    stats_.last_solve_ms = reply.solve_ms;
    lock.unlock();
    if (reply_) reply_(reply);
    lock.lock();
  }
}

KeyframeCovarianceServiceStats KeyframeCovarianceService::stats() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return stats_;
}

}  // namespace cblox
