#pragma once

#include <cstddef>
#include <cstdint>
#include <deque>
#include <optional>
#include <span>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include <absl/container/flat_hash_map.h>
#include <absl/container/flat_hash_set.h>

#include "core/maintenance/covisibility_graph.h"
#include "core/maintenance/fusion_scheduler_state.h"

namespace cblox {

/// Which keyframe of each subvolume a candidate pair's covariance is asked about.
enum class PairKeyframes {
  /// The two subvolumes' anchor keyframes (the paper's choice): the relative
  /// pose of the subvolumes' frames, which the fusion makes rigid.
  kAnchors,
  /// The pair of keyframes, one of each subvolume, that observed the most landmarks in
  /// common: where the two subvolumes overlap. The anchors when no two keyframes share a
  /// landmark. Measured on the hall (BENCHMARKS.md, "Map maintenance"): every pair of
  /// neighbours is certain where they overlap, so lap 1 fuses into one rigid subvolume
  /// before the loop closes and the loop correction can no longer bend it (RMSE as the
  /// naive map's). For comparison only.
  kMostShared,
  /// The most shared keyframes when they were made far apart in time (at least
  /// FusionSchedulerConfig::revisit_keyframe_gap keyframe ids: the overlap was seen on two
  /// passes, a revisit), else the anchors. A revisit's subvolumes overlap where their anchors
  /// need not (a 10-keyframe subvolume spans ~11 m of the town's streets), while fusing
  /// neighbours of one pass by their overlap would make the pass rigid before its loop closes
  /// (kMostShared).
  kMostSharedOnRevisits,
};

/// "anchors" | "most_shared" | "most_shared_on_revisits" (config files, logs).
const char* pairKeyframesName(PairKeyframes choice);
/// Parses pairKeyframesName's names; false for anything else.
bool parsePairKeyframes(const std::string& name, PairKeyframes* choice);

/// Settings of the map maintenance's fusion decisions (FusionScheduler).
struct FusionSchedulerConfig {
  /// Off: no candidate is ever proposed (the graph is still kept).
  bool enabled = true;
  /// Which covisibility edges are candidates.
  CovisibilityGraphConfig candidates;
  /// A pair is fused when q = 1 / ||Sigma_{i|j}||_2 >= q_min. Units: 1/m^2 or 1/rad^2
  /// (the largest eigenvalue of the 6x6 conditional covariance, whose tangent mixes metres
  /// and radians): 3e3 means no direction is less certain than 1.8 cm or 0.018 rad (1 deg)
  /// of standard deviation. > 0. Default 3e3: on the room, hall and town it fused more than
  /// 1e4 at the same map accuracy in every run (room 48 % of the unfused size against 67 %,
  /// hall 84 % against 91 %, town 54 % against 76 %; BENCHMARKS.md, "Table II from stereo
  /// depth").
  double q_min = 3e3;
  /// Which keyframes q is computed for (see PairKeyframes). Default kMostSharedOnRevisits:
  /// the anchors' fusions on one pass, and revisits that the anchors miss (town loop route
  /// 43 % of the unfused size against 52 %, second route 71 % against 74 %, room and hall
  /// unchanged; BENCHMARKS.md, "Which keyframes q is asked about").
  PairKeyframes pair_keyframes = PairKeyframes::kMostSharedOnRevisits;
  /// With kMostSharedOnRevisits: the most shared keyframes are asked about when their ids
  /// differ by at least this much (>= 1).
  int revisit_keyframe_gap = 30;
  /// At most this many pairs per covariance request (>= 1).
  int max_pairs_per_request = 8;
  /// A request without a reply is abandoned after this long, seconds (> 0): another request
  /// may be sent and its pairs may be requested again. Its reply, if it still comes, is used
  /// (see FusionScheduler::onReply). A fresh linearization of the tracker's whole map takes
  /// 0.1-0.5 s at 1000 town keyframes on an idle core and up to 23 s on a loaded one
  /// (measured with cblox-bench-maintenance), so a short timeout only repeats the work.
  double reply_timeout_s = 10.0;
  /// A pair rejected (q too small, or an error) is not requested again for this long,
  /// seconds (>= 0): BA may make it certain later, but not within a few keyframes.
  double retry_after_s = 5.0;
  /// A pair rejected by q k times in a row waits retry_after_s * 2^(k-1), at most this long,
  /// seconds (>= retry_after_s): pairs that stay uncertain are asked less and less often.
  /// Errors and failed fusions wait retry_after_s and do not count.
  double max_retry_after_s = 60.0;

  /// Empty when valid, else a message naming the first bad field. Thread-safe.
  std::string validate() const;
};

/// A pair chosen for fusion: `newer` (the later-created subvolume) is to be fused into
/// `older`. The covariance asked for is Sigma_{newer_keyframe | older_keyframe}: the
/// uncertainty of a keyframe of the newer subvolume with one of the older held fixed
/// (FusionSchedulerConfig::pair_keyframes says which), i.e. of the relative pose the fusion
/// bakes into the voxels.
struct FusionPair {
  int64_t older = 0;
  int64_t newer = 0;
  int64_t older_keyframe = 0;
  int64_t newer_keyframe = 0;
  int shared_landmarks = 0;  ///< W between the two subvolumes
  /// Landmarks both chosen keyframes observed (0 when the anchors are asked about).
  int keyframe_shared_landmarks = 0;
};

/// One covariance request to send: its id and pairs (in reply order).
struct FusionCovarianceRequest {
  int64_t request_id = 0;
  std::vector<FusionPair> pairs;
};

/// The answer for one requested pair (from the covariance service).
struct FusionCovarianceAnswer {
  bool ok = false;
  std::string error;  ///< why not, when !ok
  double q = 0.0;     ///< 1 / ||Sigma_{i|j}||_2 when ok
};

/// Counters since construction. Exact.
struct FusionSchedulerStats {
  uint64_t candidates = 0;          ///< distinct candidate pairs ever proposed in a request
  uint64_t requested = 0;           ///< pairs sent in covariance requests (repeats included)
  uint64_t accepted = 0;            ///< pairs with q >= q_min handed on for fusion
  uint64_t rejected_by_q = 0;       ///< pairs answered with q < q_min
  uint64_t covariance_errors = 0;   ///< pairs answered with an error
  uint64_t requests_timed_out = 0;  ///< requests abandoned without a reply
  uint64_t replies_ignored = 0;     ///< replies to no request in flight or kept (duplicate)
  uint64_t late_replies = 0;        ///< replies to a timed-out request, used (onReply)
  uint64_t same_anchor = 0;         ///< pairs handed on without a covariance (takeSameAnchorPairs)
  uint64_t fused = 0;               ///< fusions reported done (onFused)
  uint64_t fusions_failed = 0;      ///< fusions reported failed (onFusionFailed)

  /// Pairs asked, handed on and decided, summed: every count in it only grows, so an
  /// unchanged sum means maintenance did nothing in between.
  uint64_t progress() const { return requested + same_anchor + fused + fusions_failed; }
};

/// The map maintenance's fusion bookkeeping (issue 6, item 4), free of threads and I/O:
/// it keeps the subvolume covisibility graph, proposes candidate pairs for covariance
/// requests, turns answers into fusion orders (q >= q_min) and follows the fusions through.
///
/// Rules:
/// - Candidates are the graph's edges that meet `candidates`, strongest first, excluding the
///   active subvolume (never fused while integrated), subvolumes that are part of a fusion
///   in progress, pairs still waiting after a rejection (retry_after_s, doubling per rejection
///   by q up to max_retry_after_s), and subvolumes already used by
///   an earlier pair of the same request (each appears at most once per request, so one
///   fusion cannot remove a subvolume another pair of the batch needs).
/// - Pairs that takeSameAnchorPairs fuses without a covariance (the same anchor, or the
///   newer's anchor already fused into the older) are never requested.
/// - At most one request is in flight; nextRequest() returns nothing until its reply came
///   or it timed out. The last kKeptTimedOut timed-out requests are kept: a late reply to
///   one is used like a timely one (the answers are as valid; only the slot was freed).
/// - A pair accepted for fusion locks both subvolumes until onFused / onFusionFailed.
///   onFused merges the graph vertices (the older takes the union) and forgets the newer.
/// Time is passed in by the caller (seconds of a monotonic clock) so tests are exact.
/// Thread-safety: none (owned by the mapper's maintenance thread, or guarded by a mutex).
class FusionScheduler {
 public:
  /// Throws std::invalid_argument with validate()'s message.
  explicit FusionScheduler(const FusionSchedulerConfig& config);

  /// A new subvolume anchored at `anchor_keyframe`. Ids must increase with creation time
  /// (SubmapCollection's ids do); a known id only updates the anchor.
  void addSubvolume(int64_t subvolume, int64_t anchor_keyframe);
  /// Keyframe `keyframe` (>= 0, or KeyframeLandmarks::kUnknownKeyframe) contributed to
  /// `subvolume` and observed these landmarks (any order; duplicates, and ones already held
  /// for the keyframe, are ignored). Unknown subvolumes are ignored (returns false).
  bool addKeyframeLandmarks(int64_t subvolume, int64_t keyframe,
                            std::span<const uint64_t> landmark_ids);
  /// A new subvolume anchored at the anchor keyframe of `home` (a known subvolume): a revisit
  /// subvolume (SubmapCreationPolicyConfig::revisit_after_frames). Like addSubvolume, and the
  /// anchor keyframe's landmarks held for `home` are held for it too (it observed them), so
  /// the two share them in the graph. False (nothing added) when `home` is unknown.
  bool addSubvolumeSharingAnchor(int64_t subvolume, int64_t home);
  /// The subvolume left the map by other means (e.g. removed); pairs in flight that name it
  /// are dropped when answered.
  void removeSubvolume(int64_t subvolume);

  /// Pairs to fuse at once, without a covariance, among the subvolumes that are not
  /// `active_subvolume` (or -1) and not in a fusion:
  /// - two subvolumes anchored at the same keyframe: their relative pose is the identity,
  ///   exactly (q is infinite). Per anchor, the two oldest form a pair (newer into older).
  /// - a subvolume anchored at keyframe A, when a subvolume anchored at A was fused into an
  ///   older one O (onFused; O may since have been fused further: the one holding it now),
  ///   and none anchored at A is older than it: it goes into O. Its anchor's relative pose to
  ///   O's was accepted when that fusion was (q >= q_min or exact), and the fusion uses the
  ///   current estimate of it, as that one did. older_keyframe is then O's anchor.
  /// Each subvolume is in at most one pair per call; each returned pair locks both until
  /// onFused / onFusionFailed, as an accepted pair does. Counted in stats().same_anchor (not
  /// in accepted). None when config().enabled is false. O(subvolumes).
  std::vector<FusionPair> takeSameAnchorPairs(int64_t active_subvolume);

  /// The next request to send, if any candidate is eligible (see the class rules);
  /// `active_subvolume` (or -1) is excluded. Expires a timed-out request first.
  std::optional<FusionCovarianceRequest> nextRequest(int64_t active_subvolume, double now_s);
  /// The answers to request `request_id`, one per pair in order. Returns the pairs to fuse
  /// (q >= q_min, both subvolumes still known and not in another fusion). A reply to one of
  /// the kept timed-out requests is handled the same way (counted as late; the request in
  /// flight, if any, stays). A reply to no request in flight or kept returns nothing
  /// (counted); a reply with the wrong number of answers counts every pair as an error.
  std::vector<FusionPair> onReply(int64_t request_id,
                                  std::span<const FusionCovarianceAnswer> answers, double now_s);
  /// The fusion of `pair` is done: newer is gone, older holds both.
  void onFused(const FusionPair& pair);
  /// The fusion of `pair` did not happen (e.g. a subvolume vanished); both are free again and
  /// the pair waits retry_after_s.
  void onFusionFailed(const FusionPair& pair, double now_s);

  /// The keyframe pair (older's, newer's) that observed the most landmarks in common, with
  /// that count; the anchors and 0 when no two keyframes of theirs share one. Keyframes whose
  /// id is unknown are not candidates. Both subvolumes must be known. Ties go to the lowest
  /// older keyframe id, then the lowest newer one. Cost: O(sum of the two subvolumes'
  /// keyframe landmark set sizes x keyframes observing a landmark).
  std::tuple<int64_t, int64_t, int> mostSharedKeyframes(int64_t older, int64_t newer) const;

  /// What a resumed scheduler needs (fusion_scheduler_state.h): every known subvolume's
  /// keyframe landmark sets and every pair's back-off, its wait as seconds left after `now_s` (0
  /// when over). Requests in flight and fusions in progress are not included.
  FusionSchedulerState exportState(double now_s) const;
  /// Restores a state exported by exportState (maybe by another process, whose clock is not
  /// this one: waits count from `now_s`). Only subvolumes known here (addSubvolume) take their
  /// landmarks, only pairs of two known subvolumes their back-off; the rest is ignored.
  /// Returns the number of entries ignored. Call on a scheduler that has seen no landmarks
  /// and no replies (right after addSubvolume of the loaded subvolumes): then
  /// exportState(now_s) returns `state` minus the ignored entries, and the graph equals the
  /// exported one. Precondition: state.validate() is empty.
  size_t restoreState(const FusionSchedulerState& state, double now_s);

  const SubvolumeCovisibilityGraph& graph() const { return graph_; }
  const FusionSchedulerStats& stats() const { return stats_; }
  const FusionSchedulerConfig& config() const { return config_; }
  /// True while a request waits for its reply.
  bool requestInFlight() const { return in_flight_.has_value(); }
  /// Number of pairs accepted and not yet reported fused or failed.
  size_t fusionsInProgress() const { return fusing_pairs_; }

  /// Timed-out requests kept for their late replies (the oldest is forgotten first).
  static constexpr size_t kKeptTimedOut = 4;

 private:
  struct InFlight {
    FusionCovarianceRequest request;
    double sent_s = 0.0;
  };
  using PairKey = std::pair<int64_t, int64_t>;  // (older, newer)
  // A pair handed on for fusion: both are locked until onFused / onFusionFailed, and its
  // back-off is forgotten.
  void lockForFusion(const FusionPair& pair);
  // True for a pair takeSameAnchorPairs fuses without a covariance (both known).
  bool fusedWithoutCovariance(int64_t older, int64_t newer) const;

  FusionSchedulerConfig config_;
  SubvolumeCovisibilityGraph graph_;
  absl::flat_hash_map<int64_t, int64_t> anchors_;  // subvolume -> anchor keyframe
  // anchor keyframe of a subvolume fused away -> the subvolume holding its voxels now
  absl::flat_hash_map<int64_t, int64_t> absorbed_;
  // subvolume -> its keyframes' landmark sets, ascending keyframe ids, sets ascending
  absl::flat_hash_map<int64_t, std::vector<KeyframeLandmarks>> keyframes_;
  absl::flat_hash_set<int64_t> fusing_;            // subvolumes in an accepted pair
  absl::flat_hash_map<PairKey, double> retry_at_;  // pair -> earliest next request
  absl::flat_hash_map<PairKey, int> rejections_;   // pair -> rejections by q in a row
  absl::flat_hash_set<PairKey> proposed_;          // pairs ever requested
  std::optional<InFlight> in_flight_;
  std::deque<FusionCovarianceRequest> timed_out_;  // newest last, at most kKeptTimedOut
  int64_t next_request_id_ = 1;
  size_t fusing_pairs_ = 0;
  FusionSchedulerStats stats_;
};

}  // namespace cblox
