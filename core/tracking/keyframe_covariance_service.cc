#include "core/tracking/keyframe_covariance_service.h"

#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <limits>
#include <memory>
#include <optional>
#include <shared_mutex>
#include <stdexcept>
#include <utility>

#include <Eigen/Eigenvalues>

#include "core/common/thread_name.h"
#include "core/covariance/batch_covariance_solver.h"
#include "core/covariance/constrained_ordering_solver.h"
#include "core/covariance/kaess_recovery_solver.h"
#include "core/covariance/sparse_solve_solver.h"
#include "core/geometry/se3_adjoint.h"
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
  if (!(max_linearization_age_s >= 0.0) || !std::isfinite(max_linearization_age_s)) {
    return "max_linearization_age_s must be finite and >= 0";
  }
  if (!(min_linearization_interval_s >= 0.0) || !std::isfinite(min_linearization_interval_s)) {
    return "min_linearization_interval_s must be finite and >= 0";
  }
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

// A keyframe asked about, as the linearization sees it: `block` is the keyframe itself, or
// for a culled keyframe the first keyframe up its chain of parents that is the gauge or has a
// block in S, and T_B_K its pose relative to that one (the product of T_parent_this).
struct ResolvedKeyframe {
  uint64_t block = 0;
  bool tied = false;  // culled: moved rigidly with `block`
  Transformationd T_B_K;
};

// `id` as a linearization with gauge `gauge` and reduced camera matrix S sees it. Map's
// shared lock.
ResolvedKeyframe resolveKeyframe(const SparseMap& map, uint64_t gauge, const ReducedCameraMatrix& S,
                                 uint64_t id) {
  ResolvedKeyframe r;
  r.block = id;
  const std::optional<KeyframeAncestor> a =
      SparseMap::goodAncestor(map.keyframe(static_cast<KeyframeId>(id)), [&](const Keyframe& k) {
        return k.id == static_cast<KeyframeId>(gauge) || S.blockOf(k.id) >= 0;
      });
  if (!a || a->ancestor->id == static_cast<KeyframeId>(id)) return r;  // unknown, or itself
  r.block = static_cast<uint64_t>(a->ancestor->id);
  r.tied = true;
  r.T_B_K = a->T_A_K;
  return r;
}

// The pair's answer for culled keyframes from the answer of their blocks' pair `inner`:
// delta_I = Ad(T_I_B) delta_B (core/geometry/se3_adjoint.h), so Sigma_{I|J} = Ad Sigma Ad^T;
// conditioning on J is conditioning on its block, to which it is rigidly tied.
ConditionalCovariance throughBlocks(const KeyframePair& pair, const ResolvedKeyframe& i,
                                    const ResolvedKeyframe& j, const ConditionalCovariance& inner) {
  ConditionalCovariance r = inner;
  r.i = pair.i;
  r.j = pair.j;
  if (!inner.ok && (i.tied || j.tied)) {
    r.error = "through keyframes " + std::to_string(inner.i) + " and " + std::to_string(inner.j) +
              " (culled ones are tied to them): " + inner.error;
    return r;
  }
  if (i.tied) {
    const Eigen::Matrix<double, 6, 6> Ad = adjoint(i.T_B_K.inverse());
    r.sigma = Ad * inner.sigma * Ad.transpose();
    r.sigma = (0.5 * (r.sigma + r.sigma.transpose())).eval();
    const double largest =
        Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 6, 6>>(r.sigma, Eigen::EigenvaluesOnly)
            .eigenvalues()
            .maxCoeff();
    if (!(largest > 0.0) || !std::isfinite(largest)) {
      return failedPair(pair, "Sigma through culled keyframe " + std::to_string(inner.i) +
                                  " is not positive definite");
    }
    r.q = 1.0 / largest;
  }
  return r;
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
  thread_ = std::thread([this] {
    nameThisThread("cblox-covar");
    loop();
  });
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

struct KeyframeCovarianceService::Linearization {
  std::chrono::steady_clock::time_point built;
  int change_index = 0;
  std::string error;   // non-empty: every pair fails with it (the map cannot be linearised)
  uint64_t gauge = 0;  // the keyframe held fixed
  int keyframes = 0, landmarks = 0;
  double build_ms = 0.0;
  std::unique_ptr<ConditionalCovarianceSolver> solver;  // holds S
  const ReducedCameraMatrix& S() const { return solver->reducedCameraMatrix(); }
};

std::unique_ptr<KeyframeCovarianceService::Linearization> KeyframeCovarianceService::linearize()
    const {
  auto lin = std::make_unique<Linearization>();
  const auto start = std::chrono::steady_clock::now();
  lin->built = start;
  const MapBaProblem map_problem = buildMapBaProblem(map_, camera_, pyramid_, nullptr);
  lin->change_index = map_problem.change_index;
  lin->landmarks = static_cast<int>(map_problem.problem.landmarks.size());
  if (map_problem.problem.keyframes.size() < 2 || map_problem.problem.observations.empty()) {
    lin->error = "the map has fewer than two keyframes";
    return lin;
  }
  for (const BaKeyframe& k : map_problem.problem.keyframes) {
    if (k.fixed) lin->gauge = k.id;
  }
  lin->solver = makeSolver(
      config_.method,
      reduceCameraMatrix(linearizeBundleAdjustment(map_problem.problem, {}, config_.linearization),
                         config_.reduction));
  lin->keyframes = lin->S().numBlocks();
  lin->build_ms = msSince(start);
  return lin;
}

bool KeyframeCovarianceService::reusable(const Linearization& lin,
                                         const KeyframeCovarianceRequest& request) const {
  if (!lin.error.empty()) return false;
  if (config_.max_linearization_age_s <= 0.0) return false;  // exactly: never reused
  if (std::chrono::duration<double>(std::chrono::steady_clock::now() - lin.built).count() >
      config_.max_linearization_age_s) {
    return false;
  }
  // No loop closure or global BA since, and every keyframe asked about has a block in it
  // (culled ones through the keyframe they are tied to: the ties never change).
  std::shared_lock<std::shared_mutex> map_lock(map_.mutex());
  if (map_.changeIndex() != lin.change_index) return false;
  for (const KeyframePair& pair : request.pairs) {
    for (const uint64_t id : {pair.i, pair.j}) {
      const uint64_t block = resolveKeyframe(map_, lin.gauge, lin.S(), id).block;
      if (block != lin.gauge && lin.S().blockOf(block) < 0) return false;
    }
  }
  return true;
}

KeyframeCovarianceReply KeyframeCovarianceService::answer(const KeyframeCovarianceRequest& request,
                                                          Linearization& lin) const {
  KeyframeCovarianceReply reply;
  reply.request_id = request.request_id;
  reply.keyframes = lin.keyframes;
  reply.landmarks = lin.landmarks;
  if (!lin.error.empty()) {
    reply.results = failAll(request.pairs, lin.error);
    return reply;
  }
  const auto solve_start = std::chrono::steady_clock::now();
  reply.linearization_age_ms =
      std::chrono::duration<double, std::milli>(solve_start - lin.built).count();
  // Culled keyframes are asked about through the keyframes they are tied to.
  std::vector<std::pair<ResolvedKeyframe, ResolvedKeyframe>> resolved;
  resolved.reserve(request.pairs.size());
  {
    std::shared_lock<std::shared_mutex> map_lock(map_.mutex());
    for (const KeyframePair& pair : request.pairs) {
      resolved.emplace_back(resolveKeyframe(map_, lin.gauge, lin.S(), pair.i),
                            resolveKeyframe(map_, lin.gauge, lin.S(), pair.j));
    }
  }
  std::vector<size_t> other_pairs;
  std::vector<KeyframePair> others;
  reply.results.resize(request.pairs.size());
  for (size_t p = 0; p < request.pairs.size(); ++p) {
    const KeyframePair& pair = request.pairs[p];
    const auto& [i, j] = resolved[p];
    const KeyframePair blocks{i.block, j.block};
    if (pair.i != pair.j && i.block == j.block) {
      // Tied to one keyframe: their relative pose is exact.
      ConditionalCovariance& r = reply.results[p];
      r.i = pair.i;
      r.j = pair.j;
      r.ok = true;
      r.sigma.setZero();
      r.q = std::numeric_limits<double>::max();
    } else if (blocks.j == lin.gauge && blocks.i != lin.gauge) {
      // Given the gauge (held fixed, so S^-1 is already conditioned on it, and it has no
      // block in S) the answer is the marginal [S^-1]_ii.
      reply.results[p] = throughBlocks(pair, i, j, lin.solver->marginal(blocks));
    } else {
      other_pairs.push_back(p);
      others.push_back(blocks);
    }
  }
  if (!others.empty()) {
    const std::vector<ConditionalCovariance> other_results = lin.solver->compute(others);
    for (size_t k = 0; k < other_pairs.size(); ++k) {
      const size_t p = other_pairs[k];
      reply.results[p] =
          throughBlocks(request.pairs[p], resolved[p].first, resolved[p].second, other_results[k]);
    }
  }
  reply.solve_ms = msSince(solve_start);
  return reply;
}

KeyframeCovarianceReply KeyframeCovarianceService::compute(
    const KeyframeCovarianceRequest& request) const {
  std::unique_ptr<Linearization> lin;
  try {
    lin = linearize();
  } catch (const std::exception& e) {
    KeyframeCovarianceReply reply;
    reply.request_id = request.request_id;
    reply.results = failAll(request.pairs, std::string("linearization failed: ") + e.what());
    return reply;
  }
  KeyframeCovarianceReply reply = answer(request, *lin);
  reply.build_ms = lin->build_ms;
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
    busy_ = true;
    lock.unlock();
    KeyframeCovarianceReply reply;
    bool fresh = false;
    bool stopping = false;
    if (!kept_ || !reusable(*kept_, request)) {
      kept_.reset();
      if (!waitForLinearizationSlot()) {
        stopping = true;
        reply.request_id = request.request_id;
        reply.results = failAll(request.pairs, "covariance service stopping");
      } else {
        try {
          last_linearization_ = std::chrono::steady_clock::now();
          kept_ = linearize();
          fresh = true;
        } catch (const std::exception& e) {
          reply.request_id = request.request_id;
          reply.results = failAll(request.pairs, std::string("linearization failed: ") + e.what());
        }
      }
    }
    if (kept_ && !stopping) {
      reply = answer(request, *kept_);
      reply.reused = !fresh;
      if (fresh) reply.build_ms = kept_->build_ms;
    }
    lock.lock();
    ++stats_.answered;
    if (kept_) ++(fresh ? stats_.linearizations : stats_.reused);
    for (const ConditionalCovariance& r : reply.results)
      ++(r.ok ? stats_.pairs_ok : stats_.pairs_failed);
    if (fresh) stats_.last_build_ms = reply.build_ms;
    stats_.last_solve_ms = reply.solve_ms;
    lock.unlock();
    if (reply_) reply_(reply);
    lock.lock();
    busy_ = false;
    idle_cv_.notify_all();
  }
  idle_cv_.notify_all();
}

bool KeyframeCovarianceService::waitForLinearizationSlot() {
  if (config_.min_linearization_interval_s <= 0.0 || !last_linearization_) return true;
  const auto due = *last_linearization_ +
                   std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                       std::chrono::duration<double>(config_.min_linearization_interval_s));
  const auto start = std::chrono::steady_clock::now();
  if (start >= due) return true;
  std::unique_lock<std::mutex> lock(mutex_);
  const bool stopped = cv_.wait_until(lock, due, [this] { return stop_; });
  ++stats_.linearizations_delayed;
  stats_.delayed_ms += msSince(start);
  return !stopped;
}

void KeyframeCovarianceService::waitUntilIdle() const {
  std::unique_lock<std::mutex> lock(mutex_);
  idle_cv_.wait(lock, [this] { return stop_ || !started_ || (queue_.empty() && !busy_); });
}

KeyframeCovarianceServiceStats KeyframeCovarianceService::stats() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return stats_;
}

}  // namespace cblox
