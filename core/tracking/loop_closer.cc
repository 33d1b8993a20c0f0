#include "core/tracking/loop_closer.h"

#include <algorithm>
#include <chrono>
#include <map>
#include <optional>
#include <set>
#include <sstream>
#include <stdexcept>

#include <Eigen/Geometry>

#include "core/common/thread_name.h"
#include "core/optimization/pose_optimizer.h"
#include "core/tracking/feature_matcher.h"
#include "core/tracking/feature_measurement.h"
#include "core/tracking/frame.h"
#include "core/tracking/landmark_fusion.h"
#include "core/tracking/map_ba_problem.h"
#include "core/tracking/solved_poses.h"

namespace cblox {

std::string LoopCloserConfig::validate() const {
  std::ostringstream error;
  if (min_keyframes_between_loops < 0) {
    error << "min_keyframes_between_loops must be >= 0, got " << min_keyframes_between_loops;
  } else if (consistency_threshold < 0) {
    error << "consistency_threshold must be >= 0, got " << consistency_threshold;
  } else if (min_bow_matches < 3 || min_ransac_inliers < 3 || min_projection_matches < 3) {
    error << "min_bow_matches, min_ransac_inliers and min_projection_matches must be >= 3";
  } else if (ransac_iterations < 1) {
    error << "ransac_iterations must be >= 1, got " << ransac_iterations;
  } else if (!(max_drift_m >= 0.0) || !(max_drift_ratio >= 0.0)) {
    error << "max_drift_m and max_drift_ratio must be >= 0, got " << max_drift_m << " and "
          << max_drift_ratio;
  } else if (essential_graph_min_weight < 1) {
    error << "essential_graph_min_weight must be >= 1, got " << essential_graph_min_weight;
  } else if (std::string e = cblox::validate(pose_graph); !e.empty()) {
    error << "pose_graph: " << e;
  } else if (std::string e2 = cblox::validate(global_ba); !e2.empty()) {
    error << "global_ba: " << e2;
  }
  return error.str();
}

LoopCloser::LoopCloser(SparseMap* map, KeyframeDatabase* database, const TrackingCamera& camera,
                       const ScalePyramid& pyramid, const LoopCloserConfig& config)
    : map_(map),
      database_(database),
      camera_(camera),
      pyramid_(pyramid),
      config_(config),
      rng_state_(config.seed == 0 ? 1u : config.seed) {
  if (map == nullptr || database == nullptr) {
    throw std::invalid_argument("LoopCloser: map and database must not be null");
  }
  if (std::string e = camera.validate(); !e.empty()) {
    throw std::invalid_argument("LoopCloser: camera: " + e);
  }
  if (std::string e = config.validate(); !e.empty()) {
    throw std::invalid_argument("LoopCloser: " + e);
  }
}

void LoopCloser::insertKeyframe(Keyframe* keyframe) { queue_.push(keyframe); }

LoopCloser::~LoopCloser() { abortGlobalBundleAdjustment(); }

void LoopCloser::stop() {
  queue_.stop();
  abortGlobalBundleAdjustment();
}

void LoopCloser::waitUntilIdle() {
  queue_.waitUntilIdle();
  std::unique_lock<std::mutex> lock(gba_mutex_);
  gba_cv_.wait(lock, [this] { return !gba_running_; });
}

void LoopCloser::abortGlobalBundleAdjustment() {
  std::thread running;
  {
    std::lock_guard<std::mutex> lock(gba_mutex_);
    running = std::move(gba_thread_);
  }
  if (!running.joinable()) return;
  abort_gba_ = true;
  running.join();  // not under gba_mutex_: the thread takes it when it ends
  abort_gba_ = false;
}

void LoopCloser::startGlobalBundleAdjustment(Keyframe* loop_keyframe) {
  std::lock_guard<std::mutex> lock(gba_mutex_);
  gba_running_ = true;
  gba_thread_ = std::thread([this, loop_keyframe] {
    nameThisThread("cblox-globalba");
    globalBundleAdjustment(loop_keyframe);
    std::lock_guard<std::mutex> done(gba_mutex_);
    gba_running_ = false;
    gba_cv_.notify_all();
  });
}

void LoopCloser::run() {
  while (queue_.waitForWork()) processOne();
}

LoopCloserStats LoopCloser::stats() const {
  std::lock_guard<std::mutex> lock(stats_mutex_);
  return stats_;
}

bool LoopCloser::processOne() {
  Keyframe* keyframe = queue_.tryPop();
  if (keyframe == nullptr) return false;
  const std::vector<Keyframe*> candidates = detect(keyframe);
  {
    std::lock_guard<std::mutex> lock(stats_mutex_);
    ++stats_.keyframes_checked;
    stats_.candidates_detected += candidates.size();
  }
  if (!candidates.empty()) {
    if (const std::optional<Verified> loop = verify(keyframe, candidates)) {
      abortGlobalBundleAdjustment();  // its result would be stale after the correction
      correct(keyframe, *loop);
      if (config_.global_bundle_adjustment) startGlobalBundleAdjustment(loop->candidate);
    } else {
      std::lock_guard<std::mutex> lock(stats_mutex_);
      ++stats_.loops_rejected;
    }
  }
  queue_.done();
  return true;
}

std::vector<Keyframe*> LoopCloser::detect(Keyframe* keyframe) {
  std::shared_lock<std::shared_mutex> lock(map_->mutex());
  if (keyframe->bad()) return {};
  const BowVector& bow = keyframe->features().bow;
  const bool too_early =
      keyframe->id < last_loop_keyframe_ + config_.min_keyframes_between_loops ||
      static_cast<int>(map_->numKeyframes()) <= config_.min_keyframes_between_loops;
  if (too_early || bow.empty()) {
    database_->add(keyframe->id, bow);
    return {};
  }
  double min_score = 1.0;
  std::vector<KeyframeId> exclude{keyframe->id};
  for (const auto& [neighbour, weight] : keyframe->connections()) {
    exclude.push_back(neighbour->id);
    if (neighbour->bad()) continue;
    min_score = std::min(min_score, scoreL1(bow, neighbour->features().bow));
  }
  // Neighbours of a candidate: its 10 best covisible keyframes (the map's shared lock is
  // held by this thread for the whole query).
  const auto neighbours = [this](KeyframeId id) {
    std::vector<KeyframeId> ids;
    if (const Keyframe* k = map_->keyframe(id); k != nullptr && !k->bad()) {
      for (const Keyframe* n : k->bestCovisible(10)) ids.push_back(n->id);
    }
    return ids;
  };
  const std::vector<PlaceCandidate> places =
      database_->queryLoopCandidates(bow, min_score, exclude, 0, neighbours);
  database_->add(keyframe->id, bow);

  // Consistency over consecutive keyframes (ORB-SLAM2's DetectLoop).
  std::vector<ConsistentGroup> current;
  std::vector<uint8_t> extended(groups_.size(), 0);
  std::vector<Keyframe*> consistent;
  for (const PlaceCandidate& place : places) {
    Keyframe* candidate = map_->keyframe(place.id);
    if (candidate == nullptr || candidate->bad()) continue;
    std::vector<KeyframeId> group{candidate->id};
    for (const auto& [k, w] : candidate->connections()) group.push_back(k->id);
    std::sort(group.begin(), group.end());
    bool enough = false, consistent_with_some = false;
    for (size_t g = 0; g < groups_.size(); ++g) {
      std::vector<KeyframeId> common;
      std::set_intersection(group.begin(), group.end(), groups_[g].members.begin(),
                            groups_[g].members.end(), std::back_inserter(common));
      if (common.empty()) continue;
      consistent_with_some = true;
      const int consistency = groups_[g].consistency + 1;
      if (!extended[g]) {
        current.push_back({group, consistency});
        extended[g] = 1;
      }
      if (consistency >= config_.consistency_threshold && !enough) {
        consistent.push_back(candidate);
        enough = true;
      }
    }
    if (!consistent_with_some) current.push_back({group, 0});
  }
  groups_ = std::move(current);
  return consistent;
}

namespace {
// Projection search window of the verification (searchLocalLandmarks' th: 2.5 * 2.5-4 px,
// ORB-SLAM2's 10 px, times the level scale).
constexpr float kLoopProjectionWindow = 2.5f;

uint32_t nextRandom(uint32_t* state) {  // xorshift32
  uint32_t x = *state;
  x ^= x << 13;
  x ^= x >> 17;
  x ^= x << 5;
  return *state = x;
}
}  // namespace

bool LoopCloser::plausibleCorrection(const Keyframe& keyframe, const Keyframe& candidate,
                                     const Transformationd& T_C_G) const {
  // Path travelled from the candidate to the query along the keyframes in creation order.
  double path_m = 0.0;
  const Keyframe* previous = nullptr;
  for (const Keyframe* k : map_->keyframes()) {
    if (k->bad() || k->id < candidate.id || k->id > keyframe.id) continue;
    if (previous != nullptr)
      path_m += (k->T_G_C().translation() - previous->T_G_C().translation()).norm();
    previous = k;
  }
  const double correction_m =
      (T_C_G.inverse().translation() - keyframe.T_G_C().translation()).norm();
  return correction_m <= config_.max_drift_m + config_.max_drift_ratio * path_m;
}

std::optional<LoopCloser::Verified> LoopCloser::verify(Keyframe* keyframe,
                                                       const std::vector<Keyframe*>& candidates) {
  std::shared_lock<std::shared_mutex> lock(map_->mutex());
  if (keyframe->bad()) return std::nullopt;
  const FrameFeatures& f = keyframe->features();
  const StereoCameraModel model{camera_.intrinsics.fx, camera_.intrinsics.fy, camera_.intrinsics.cx,
                                camera_.intrinsics.cy, camera_.bf()};
  FeatureMatcherConfig matcher;
  matcher.nn_ratio = 0.75f;
  for (Keyframe* candidate : candidates) {
    if (candidate->bad()) continue;
    std::vector<Landmark*> matches;
    if (searchByBow(*keyframe, *candidate, matcher, &matches) < config_.min_bow_matches) continue;
    // 3D-3D pairs: the query feature's point in its camera (stereo depth, else its own
    // landmark) and the candidate's landmark in G.
    std::vector<size_t> index;
    std::vector<Eigen::Vector3d> p_C, p_G;
    for (size_t i = 0; i < matches.size(); ++i) {
      if (matches[i] == nullptr) continue;
      Eigen::Vector3d p;
      if (f.hasDepth(i)) {
        p = f.unproject(i, camera_);
      } else if (const Landmark* own = keyframe->landmark(i); own != nullptr && !own->bad()) {
        p = keyframe->T_C_G() * own->position();
      } else {
        continue;
      }
      index.push_back(i);
      p_C.push_back(p);
      p_G.push_back(matches[i]->position());
    }
    const int n = static_cast<int>(index.size());
    if (n < config_.min_ransac_inliers) continue;
    auto inliersOf = [&](const Transformationd& T_C_G, std::vector<uint8_t>* flags) {
      int count = 0;
      flags->assign(static_cast<size_t>(n), 0);
      for (int k = 0; k < n; ++k) {
        const Eigen::Vector3d q = T_C_G * p_G[static_cast<size_t>(k)];
        if (!(q.z() > 0.0)) continue;
        const Keypoint& kp = f.keypoints[index[static_cast<size_t>(k)]];
        const double du = model.fx * q.x() / q.z() + model.cx - kp.u;
        const double dv = model.fy * q.y() / q.z() + model.cy - kp.v;
        if ((du * du + dv * dv) * pyramid_.invSigma2(kp.octave) < 9.21) {
          (*flags)[static_cast<size_t>(k)] = 1;
          ++count;
        }
      }
      return count;
    };
    int best_count = 0;
    Transformationd best_T_C_G;
    std::vector<uint8_t> flags, best_flags;
    for (int it = 0; it < config_.ransac_iterations; ++it) {
      Eigen::Matrix3d src, dst;
      int a = static_cast<int>(nextRandom(&rng_state_) % static_cast<uint32_t>(n));
      int b = static_cast<int>(nextRandom(&rng_state_) % static_cast<uint32_t>(n));
      int c = static_cast<int>(nextRandom(&rng_state_) % static_cast<uint32_t>(n));
      if (a == b || b == c || a == c) continue;
      src << p_C[static_cast<size_t>(a)], p_C[static_cast<size_t>(b)], p_C[static_cast<size_t>(c)];
      dst << p_G[static_cast<size_t>(a)], p_G[static_cast<size_t>(b)], p_G[static_cast<size_t>(c)];
      const Eigen::Matrix4d T_G_C = Eigen::umeyama(src, dst, false);
      if (!T_G_C.allFinite()) continue;
      const Transformationd T_C_G = Transformationd::fromMatrix(T_G_C).inverse();
      const int count = inliersOf(T_C_G, &flags);
      if (count > best_count) {
        best_count = count;
        best_T_C_G = T_C_G;
        best_flags = flags;
      }
    }
    if (best_count < config_.min_ransac_inliers) continue;
    // Refine on the inliers with the motion-only optimiser.
    std::vector<PoseObservation> observations;
    std::vector<size_t> observed;
    for (int k = 0; k < n; ++k) {
      if (!best_flags[static_cast<size_t>(k)]) continue;
      const size_t i = index[static_cast<size_t>(k)];
      observations.push_back(poseObservation(f, i, pyramid_, p_G[static_cast<size_t>(k)]));
      observed.push_back(i);
    }
    const PoseOptimizationResult refined = optimizePose(model, best_T_C_G, observations);
    if (refined.num_inliers < config_.min_ransac_inliers) continue;
    // More matches: the candidate's covisible landmarks projected at the refined pose.
    Frame probe(keyframe->frame_id, keyframe->timestamp_ns, keyframe->sharedFeatures());
    for (size_t k = 0; k < observed.size(); ++k) {
      if (refined.inlier[k])
        probe.landmarks[observed[k]] = matches[observed[k]]->shared_from_this();
    }
    std::vector<LandmarkProjection> projections;
    std::set<const Landmark*> seen;
    std::vector<Keyframe*> group = candidate->covisibleByWeight();
    group.push_back(candidate);
    for (const Keyframe* k : group) {
      if (k->bad()) continue;
      for (Landmark* l : k->landmarks()) {
        if (l == nullptr || l->bad() || !seen.insert(l).second) continue;
        if (const auto p = projectLandmark(l, refined.T_C_G, camera_, pyramid_)) {
          projections.push_back(*p);
        }
      }
    }
    // ORB-SLAM2's window (10 px times the level scale) and close descriptors (TH_LOW); the
    // matches must then agree with one pose: a place that merely looks alike (a street
    // crossing repeated every block) gathers projection matches but not inliers.
    FeatureMatcherConfig projection_matcher;
    projection_matcher.nn_ratio = 1.0f;
    projection_matcher.max_distance = kOrbDistanceLow;
    searchLocalLandmarks(&probe, projections, kLoopProjectionWindow, projection_matcher, pyramid_);
    std::vector<PoseObservation> all;
    std::vector<size_t> all_index;
    for (size_t i = 0; i < probe.size(); ++i) {
      if (!probe.landmarks[i] || probe.landmarks[i]->bad()) continue;
      all.push_back(poseObservation(f, i, pyramid_, probe.landmarks[i]->position()));
      all_index.push_back(i);
    }
    if (static_cast<int>(all.size()) < config_.min_projection_matches) continue;
    const PoseOptimizationResult checked = optimizePose(model, refined.T_C_G, all);
    if (checked.num_inliers < config_.min_projection_matches) continue;
    if (!plausibleCorrection(*keyframe, *candidate, checked.T_C_G)) {
      std::lock_guard<std::mutex> stats_lock(stats_mutex_);
      ++stats_.loops_rejected_drift;
      continue;
    }
    Verified v;
    v.matches.assign(f.size(), nullptr);
    for (size_t k = 0; k < all_index.size(); ++k) {
      if (checked.inlier[k]) v.matches[all_index[k]] = probe.landmarks[all_index[k]];
    }
    v.candidate = candidate;
    v.T_C_G = checked.T_C_G;
    v.inliers = checked.num_inliers;
    return v;
  }
  return std::nullopt;
}

void LoopCloser::correct(Keyframe* keyframe, const Verified& loop) {
  const auto start = std::chrono::steady_clock::now();
  double locked_ms = 0.0;
  const auto msSince = [](std::chrono::steady_clock::time_point since) {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - since)
        .count();
  };
  LoopClosureEvent event;
  KeyframePoseBatch group_batch, batch;
  // The essential graph, read in phase A and solved in phase B without the map's lock.
  std::vector<Keyframe*> graph_keyframes;  // vertex index -> keyframe
  std::vector<PoseGraphVertex> vertices;
  std::vector<PoseGraphEdge> edges;
  // Landmarks moved with a group keyframe in phase A follow that keyframe in phase C, not
  // their reference keyframe (ORB-SLAM2's mnCorrectedReference): else they would be corrected
  // twice. Keyed by id: a landmark a fusion retires is freed, and its address may be reused.
  std::map<LandmarkId, const Keyframe*> corrected_with;

  // Phase A, under the exclusive lock: the query keyframe's covisible group is moved rigidly
  // with it, the loop's landmarks are fused, and the essential graph is read.
  {
    const auto locked = std::chrono::steady_clock::now();
    std::unique_lock<std::shared_mutex> lock(map_->mutex());
    if (keyframe->bad() || loop.candidate->bad()) return;
    map_->bumpChangeIndex();
    const std::vector<Keyframe*> all = map_->keyframes();
    KeyframePoses old_T_C_G;
    for (const Keyframe* k : all) old_T_C_G[k] = k->T_C_G();

    // 1. Move the query keyframe's covisible group rigidly with it.
    std::vector<Keyframe*> group = keyframe->covisibleByWeight();
    group.push_back(keyframe);
    std::set<const Keyframe*> in_group(group.begin(), group.end());
    const Transformationd T_G_Ckf_old = keyframe->T_G_C();
    event.correction_m = (loop.T_C_G.inverse().translation() - T_G_Ckf_old.translation()).norm();
    for (Keyframe* k : group) {
      const Transformationd T_Ck_Ckf = k->T_C_G() * T_G_Ckf_old;
      const Transformationd corrected = T_Ck_Ckf * loop.T_C_G;
      const Transformationd T_G_Ck_new = corrected.inverse();
      for (Landmark* l : k->landmarks()) {
        if (l == nullptr || l->bad() || l->corrected_by_keyframe == keyframe->id) continue;
        l->setPosition(T_G_Ck_new * (k->T_C_G() * l->position()));
        l->updateNormalAndDepth(pyramid_);
        l->corrected_by_keyframe = keyframe->id;
        corrected_with[l->id] = k;
      }
      k->setPose(corrected);
    }
    // 2. Fuse the loop's landmarks into the group (duplicates merge).
    for (size_t i = 0; i < loop.matches.size(); ++i) {
      Landmark* loop_landmark = loop.matches[i].get();
      if (loop_landmark == nullptr || loop_landmark->bad()) continue;
      Landmark* current = keyframe->landmark(i);
      if (current == loop_landmark) continue;
      if (current != nullptr) {
        map_->replaceLandmark(current, loop_landmark);
      } else if (loop_landmark->indexIn(keyframe) < 0) {
        SparseMap::addObservation(keyframe, static_cast<uint32_t>(i), loop_landmark);
      }
    }
    std::vector<Landmark*> loop_landmarks;  // held below, across the fusions
    {
      std::set<const Landmark*> seen;
      std::vector<Keyframe*> loop_group = loop.candidate->covisibleByWeight();
      loop_group.push_back(loop.candidate);
      for (const Keyframe* k : loop_group) {
        for (Landmark* l : k->landmarks()) {
          if (l != nullptr && !l->bad() && seen.insert(l).second) loop_landmarks.push_back(l);
        }
      }
    }
    const std::vector<std::shared_ptr<Landmark>> held = holdLandmarks(loop_landmarks);
    for (Keyframe* k : group) {
      if (!k->bad()) fuseLandmarks(map_, k, held, 4.0f, camera_, pyramid_);
    }
    // 3. New links made by the loop.
    std::map<Keyframe*, std::set<Keyframe*, KeyframeIdLess>, KeyframeIdLess> loop_links;
    for (Keyframe* k : group) {
      if (k->bad()) continue;
      std::set<Keyframe*, KeyframeIdLess> before(k->covisibleByWeight().begin(),
                                                 k->covisibleByWeight().end());
      k->updateConnections();
      for (Keyframe* n : k->covisibleByWeight()) {
        if (before.count(n) == 0 && in_group.count(n) == 0) loop_links[k].insert(n);
      }
    }
    // 4. The essential graph.
    std::map<const Keyframe*, int> vertex_of;
    for (Keyframe* k : all) {
      if (k->bad()) continue;
      vertex_of[k] = static_cast<int>(vertices.size());
      vertices.push_back(
          PoseGraphVertex{static_cast<uint64_t>(k->id), k->T_C_G(), k == loop.candidate});
      graph_keyframes.push_back(k);
    }
    std::set<std::pair<int, int>> added;
    auto addEdge = [&](const Keyframe* a, const Keyframe* b, const Transformationd& T_a_b) {
      const auto ia = vertex_of.find(a), ib = vertex_of.find(b);
      if (ia == vertex_of.end() || ib == vertex_of.end() || a == b) return;
      const std::pair<int, int> key{std::min(ia->second, ib->second),
                                    std::max(ia->second, ib->second)};
      if (!added.insert(key).second) return;
      edges.push_back(
          PoseGraphEdge{ia->second, ib->second, T_a_b, Eigen::Matrix<double, 6, 6>::Identity()});
    };
    // Measurements from the poses before the correction (they keep the local shape), except
    // the loop links, measured at the corrected poses.
    auto oldRelative = [&](const Keyframe* a, const Keyframe* b) {
      return old_T_C_G.at(a) * old_T_C_G.at(b).inverse();
    };
    for (const auto& [k, links] : loop_links) {
      for (Keyframe* n : links) addEdge(k, n, k->T_C_G() * n->T_G_C());
    }
    for (Keyframe* k : all) {
      if (k->bad()) continue;
      if (k->parent() != nullptr && !k->parent()->bad() && old_T_C_G.count(k->parent())) {
        addEdge(k, k->parent(), oldRelative(k, k->parent()));
      }
      for (Keyframe* l : k->loopEdges()) {
        if (old_T_C_G.count(l)) addEdge(k, l, oldRelative(k, l));
      }
      for (Keyframe* n : k->covisibleWithWeightAtLeast(config_.essential_graph_min_weight)) {
        if (old_T_C_G.count(n) && !(loop_links.count(k) && loop_links[k].count(n))) {
          addEdge(k, n, oldRelative(k, n));
        }
      }
    }
    keyframe->addLoopEdge(loop.candidate);
    loop.candidate->addLoopEdge(keyframe);
    last_loop_keyframe_ = keyframe->id;
    // The group's new poses go out now: the frames tracked during phase B are in its frame.
    for (const Keyframe* k : group) {
      if (!k->bad()) group_batch.emplace_back(k->id, k->T_G_C());
    }
    map_->moveCulledKeyframes(&group_batch);
    map_->setCorrectionPending(true);
    locked_ms += msSince(locked);
  }
  if (on_poses_ && !group_batch.empty()) on_poses_(group_batch, false);

  // Phase B, without the map's lock: the essential graph's optimisation (most of a correction:
  // 0.7 s on the town's 680 keyframes). Tracking and local mapping go on meanwhile.
  event.graph_keyframes = static_cast<int>(vertices.size());
  event.graph_edges = static_cast<int>(edges.size());
  std::optional<PoseGraphResult> graph;
  if (!edges.empty()) {
    try {
      graph = optimizePoseGraph(vertices, edges, config_.pose_graph);
      event.graph_ms = graph->time_ms;
    } catch (const std::exception&) {
      // Invalid input (a non-finite pose): the group stays corrected and the rest of the map
      // as it was; phase C still ends the correction.
      std::lock_guard<std::mutex> stats_lock(stats_mutex_);
      ++stats_.essential_graphs_failed;
    }
  }

  // Phase C, under the exclusive lock: the graph's poses are applied. A keyframe a local BA
  // moved since phase A keeps that change (relative to the graph's pose); keyframes made since
  // follow their parent; every landmark follows the keyframe that placed it (or moved it in
  // phase A).
  {
    const auto locked = std::chrono::steady_clock::now();
    std::unique_lock<std::shared_mutex> lock(map_->mutex());
    map_->bumpChangeIndex();
    map_->setCorrectionPending(false);
    if (graph) {
      std::vector<Transformationd> read;
      read.reserve(vertices.size());
      for (const PoseGraphVertex& v : vertices) read.push_back(v.T_C_G);
      applySolvedPoses(map_, graph_keyframes, read, graph->T_C_G, corrected_with, pyramid_);
    }
    for (Keyframe* k : map_->keyframes()) batch.emplace_back(k->id, k->T_G_C());
    map_->moveCulledKeyframes(&batch);
    locked_ms += msSince(locked);
  }
  event.query = keyframe->id;
  event.candidate = loop.candidate->id;
  event.inliers = loop.inliers;
  event.correction_ms = msSince(start);
  event.locked_ms = locked_ms;
  {
    std::lock_guard<std::mutex> lock(stats_mutex_);
    ++stats_.loops_closed;
    stats_.last_correction_ms = event.correction_ms;
  }
  if (on_poses_) on_poses_(batch, false);
  if (on_loop_) on_loop_(event);
}

void LoopCloser::globalBundleAdjustment(Keyframe* loop_keyframe) {
  // Gauge: the loop keyframe (fixed during the essential graph too).
  MapBaProblem map_problem = buildMapBaProblem(*map_, camera_, pyramid_, loop_keyframe);
  const BundleAdjustmentProblem& problem = map_problem.problem;
  const std::vector<Keyframe*>& keyframes = map_problem.keyframes;
  const std::vector<std::shared_ptr<Landmark>>& landmarks = map_problem.landmarks;
  const int change_index = map_problem.change_index;
  if (problem.observations.empty()) return;
  const BundleAdjustmentResult result = bundleAdjust(problem, config_.global_ba, &abort_gba_);
  const auto abandon = [this] {
    std::lock_guard<std::mutex> lock(stats_mutex_);
    ++stats_.global_bundle_adjustments_abandoned;
  };
  if (result.aborted) return abandon();
  KeyframePoseBatch batch;
  {
    std::unique_lock<std::shared_mutex> lock(map_->mutex());
    if (map_->changeIndex() != change_index || !result.success) return abandon();  // stale
    KeyframePoses old_T_C_G;
    for (size_t i = 0; i < keyframes.size(); ++i) {
      old_T_C_G[keyframes[i]] = keyframes[i]->T_C_G();
      if (!keyframes[i]->bad()) keyframes[i]->setPose(result.T_C_G[i]);
    }
    newKeyframesFollowTheirParent(*map_, &old_T_C_G);
    std::set<const Landmark*> optimised;
    for (size_t li = 0; li < landmarks.size(); ++li) {
      Landmark* l = landmarks[li].get();
      if (l->bad()) continue;
      l->setPosition(result.p_G[li]);
      l->updateNormalAndDepth(pyramid_);
      optimised.insert(l);
    }
    landmarksFollowTheirKeyframe(map_, old_T_C_G, {}, optimised, pyramid_);
    map_->bumpChangeIndex();
    for (Keyframe* k : map_->keyframes()) batch.emplace_back(k->id, k->T_G_C());
    map_->moveCulledKeyframes(&batch);
  }
  {
    std::lock_guard<std::mutex> lock(stats_mutex_);
    ++stats_.global_bundle_adjustments;
    stats_.last_global_ba_ms = result.time_ms;
  }
  if (on_poses_) on_poses_(batch, true);
}

}  // namespace cblox
