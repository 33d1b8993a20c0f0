#pragma once

#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "core/covariance/conditional_covariance.h"
#include "core/covariance/reduced_camera_matrix.h"
#include "core/features/scale_pyramid.h"
#include "core/optimization/ba_linearization.h"
#include "core/tracking/sparse_map.h"
#include "core/tracking/tracking_camera.h"

namespace cblox {

/// Which core/covariance solver answers a request.
enum class CovarianceMethod {
  kConstrainedOrdering,  ///< the paper's: one CAMD ordering + factorisation per pair
  kBatch,                ///< all keyframes of the request last in one factorisation
  kKaessRecovery,        ///< one AMD factorisation, Kaess & Dellaert recovery per pair
  kSparseSolve,          ///< one nested-dissection factorisation, sparse forward solves
};
/// "constrained_ordering", "batch", "kaess_recovery", "sparse_solve". Thread-safe.
const char* covarianceMethodName(CovarianceMethod method);

struct KeyframeCovarianceServiceConfig {
  /// kSparseSolve factorises once per linearization, so a kept linearization answers later
  /// requests with forward solves only; kBatch and kConstrainedOrdering factorise per request.
  CovarianceMethod method = CovarianceMethod::kSparseSolve;
  /// Requests waiting (the oldest is answered with an error when more arrive), >= 1.
  size_t max_queued_requests = 4;
  /// Niceness the service thread gives itself (setpriority on its thread id), [0, 19]; the
  /// tracking thread keeps its own. 0 = leave it.
  int niceness = 10;
  /// A linearization (S and the solver's factorisation) answers later requests while it is
  /// at most this old, the map has had no loop closure or global BA since
  /// (SparseMap::changeIndex), and every keyframe asked about has a block in it (a culled
  /// one through the keyframe it is tied to); otherwise the map is read and linearised again (so
  /// errors on ids are always those of the current map). 0 = a fresh linearization per request.
  /// Local BA moves poses in the meantime: this bounds how stale an answer can be.
  double max_linearization_age_s = 5.0;
  /// A fresh linearization is started no sooner than this after the previous one started; a
  /// request that needs one waits meanwhile (in the queue; the mapper uses late replies).
  /// The map's linearization and factorisation cost about 1 s of a core at the town's 1000
  /// keyframes, and a new subvolume anchor asks about a keyframe no linearization has, so
  /// without a bound the service re-linearised every 2 s there (0.35 of a core). 0 = no bound.
  double min_linearization_interval_s = 5.0;
  /// The linearization: Huber reweighting on (observations that BA would call outliers
  /// count less instead of inflating the certainty).
  BaLinearizationConfig linearization{true};
  /// Degenerate landmarks are left out of S (see ReducedCameraMatrixConfig).
  ReducedCameraMatrixConfig reduction;

  /// Empty when valid, else a message naming the first bad field. Thread-safe.
  std::string validate() const;
};

/// A request: pairs (i, j) of keyframe ids, Sigma_{i|j} wanted for each.
struct KeyframeCovarianceRequest {
  int64_t request_id = 0;
  std::vector<KeyframePair> pairs;
};

/// The answer: one result per pair in request order (errors per pair), and what it took.
struct KeyframeCovarianceReply {
  int64_t request_id = 0;
  std::vector<ConditionalCovariance> results;
  int keyframes = 0;      ///< free keyframes of the linearization (blocks of S)
  int landmarks = 0;      ///< landmarks of the problem
  double build_ms = 0.0;  ///< map -> BA problem -> Jacobian -> S (0 when reused)
  double solve_ms = 0.0;  ///< the solver over all pairs
  bool reused = false;    ///< answered from an earlier request's linearization
  /// From reading the map to solving (about build_ms for a fresh linearization).
  double linearization_age_ms = 0.0;
};

/// Counters since start. Exact.
struct KeyframeCovarianceServiceStats {
  uint64_t requests = 0;  ///< submitted
  uint64_t answered = 0;  ///< replies sent (also for dropped requests)
  uint64_t dropped = 0;   ///< answered with an error because the queue was full
  uint64_t pairs_ok = 0;
  uint64_t pairs_failed = 0;
  uint64_t linearizations = 0;  ///< map read, linearised and reduced
  uint64_t reused = 0;          ///< requests answered from an earlier linearization
  /// Linearizations that waited for min_linearization_interval_s, and how long in all.
  uint64_t linearizations_delayed = 0;
  double delayed_ms = 0.0;
  double last_build_ms = 0.0;
  double last_solve_ms = 0.0;
};

/// The tracker's covariance service (CBLOX_COV_REQUEST -> CBLOX_COV_REPLY, issue 6 item 3):
/// answers requests for conditional keyframe covariances from the current sparse map, on a
/// thread of its own at low priority, so it never delays tracking.
///
/// Per linearization: the whole map as a BA problem (buildMapBaProblem, the first keyframe
/// fixed as the gauge, as in DESIGN: conditioning on it too) read under the map's shared lock
/// (which the tracking thread also only reads under; local mapping and loop closing wait for the
/// read, a few ms), linearised at the map's current estimate (the latest local / global BA
/// solution) with Huber reweighting, S = reduceCameraMatrix, and the configured solver on S
/// (which factorises once for kKaessRecovery / kSparseSolve). A linearization is kept and
/// answers later requests under max_linearization_age_s's rules.
/// Units and convention: core/covariance/conditional_covariance.h (m^2, m*rad, rad^2;
/// tangent [rho; phi] of T_C_G's left perturbation = T_G_C's right perturbation).
/// A pair conditioned on the gauge keyframe (j = the first keyframe, which the BA holds
/// fixed) gets the marginal covariance of i, [S^-1]_ii: conditioning on the gauge is what S^-1
/// already is (ConditionalCovarianceSolver::marginal of the configured solver). Other pairs
/// go to the solver's compute(), and are conditioned on the gauge as well as on j.
/// Culled keyframes (local_mapping.cull_keyframes) are answered too: a culled
/// keyframe K is rigidly tied to B, the first keyframe up its chain of parents that is in the
/// linearization, by T_B_K (the product of T_parent_this; its pose follows B's in every
/// keyframe pose batch, SparseMap::moveCulledKeyframes), so its tangent is
/// delta_K = Ad(T_K_B) delta_B and Sigma_{K|J} = Ad Sigma_{B|J} Ad^T (core/geometry/
/// se3_adjoint.h), q recomputed from it; conditioning on a culled J is conditioning on its B. Two
/// keyframes tied to the same B (or one tied to the other) have an exactly known relative
/// pose: ok, sigma 0 and q = the largest finite double (so the mapper fuses them).
/// Errors are per pair: keyframes unknown to the map, or the gauge keyframe as i
/// ("not in the BA linearization"), i == j, S not positive definite. A request that arrives
/// when max_queued_requests are waiting pushes out the oldest, which is answered with every
/// pair failed ("dropped: service busy").
/// Thread-safety: submit() and stats() from any thread; `reply` is called on the service
/// thread (or in submit() for a dropped request).
class KeyframeCovarianceService {
 public:
  using ReplyCallback = std::function<void(const KeyframeCovarianceReply&)>;

  /// `map` must outlive the service. Throws std::invalid_argument for an invalid config.
  KeyframeCovarianceService(const SparseMap& map, const TrackingCamera& camera,
                            const ScalePyramid& pyramid,
                            const KeyframeCovarianceServiceConfig& config, ReplyCallback reply);
  ~KeyframeCovarianceService();
  KeyframeCovarianceService(const KeyframeCovarianceService&) = delete;
  KeyframeCovarianceService& operator=(const KeyframeCovarianceService&) = delete;

  /// Starts the thread (once). Thread-safe.
  void start();
  /// Answers the request in hand, drops the queued ones unanswered, joins. Idempotent.
  void stop();
  /// Queues a request. Never blocks on the computation. Thread-safe.
  void submit(KeyframeCovarianceRequest request);
  /// Waits until no request is queued or in hand (its reply callback has returned), or the
  /// service is stopped. Thread-safe; not from the reply callback.
  void waitUntilIdle() const;
  /// Computes a reply on the calling thread (what the service thread does per request),
  /// with a fresh linearization, neither using nor filling the kept one. Thread-safe with
  /// respect to the map (shared lock); not counted in stats().
  KeyframeCovarianceReply compute(const KeyframeCovarianceRequest& request) const;
  KeyframeCovarianceServiceStats stats() const;

  /// A linearization of the map and the solvers built on it (opaque).
  struct Linearization;

 private:
  void loop();
  /// The reply from `lin` (requested ids already checked against it or not: errors per pair).
  KeyframeCovarianceReply answer(const KeyframeCovarianceRequest& request,
                                 Linearization& lin) const;
  /// Reads and linearises the map; throws std::exception on failure.
  std::unique_ptr<Linearization> linearize() const;
  /// Whether `lin` may answer `request` now (age, change index, ids).
  bool reusable(const Linearization& lin, const KeyframeCovarianceRequest& request) const;

  const SparseMap& map_;
  const TrackingCamera camera_;
  const ScalePyramid pyramid_;
  const KeyframeCovarianceServiceConfig config_;
  const ReplyCallback reply_;

  mutable std::mutex mutex_;  // guards everything below
  std::condition_variable cv_;
  mutable std::condition_variable idle_cv_;
  std::deque<KeyframeCovarianceRequest> queue_;
  KeyframeCovarianceServiceStats stats_;
  bool stop_ = false, started_ = false, busy_ = false;
  std::thread thread_;
  std::unique_ptr<Linearization> kept_;  // the service thread's only
  // When the last linearization started (the service thread's only).
  std::optional<std::chrono::steady_clock::time_point> last_linearization_;
  // Waits until min_linearization_interval_s after the last linearization started; false if
  // stop() came first.
  bool waitForLinearizationSlot();
};

}  // namespace cblox
