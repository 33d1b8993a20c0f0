#pragma once

// Offline replay: an LCM log (lcm-logger's format) played through the tracker and the mapper
// in one process, as fast as the CPU allows, and deterministically.

#include <atomic>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "core/geometry/se3.h"
#include "core/mapping/mapper.h"
#include "core/vocabulary/binary_vocabulary.h"
#include "daemon/mapper/mapper_process_config.h"
#include "daemon/tracker/tracker_config.h"
#include "daemon/tracker/tracker_node.h"

namespace cblox {

/// Settings of a replay: the two processes' own settings, as their YAML files give them.
struct ReplayConfig {
  /// The log to read (lcm-logger's format).
  std::string log_path;
  /// The mapper; its pose source decides whether the tracker runs (kTracker) or the mapper
  /// takes the log's ground-truth poses (kGroundTruth). Its output_dir receives the exports.
  MapperProcessConfig mapper;
  /// The tracker (pose source kTracker only).
  TrackerProcessConfig tracker;
};

/// Where a replay is, for a progress line. Plain value type.
struct ReplayProgress {
  uint64_t events = 0;        ///< log events read
  uint64_t frames = 0;        ///< sensor frames handed over (tracker frames, else depth frames)
  double fraction = 0.0;      ///< of the log's bytes read, [0, 1]
  double elapsed_s = 0.0;     ///< wall time since the replay began
  double log_elapsed_s = 0.0; ///< log time covered (event time stamps) since the first event
};

/// One pose of the replay's trajectories. Plain value type.
struct ReplayPose {
  int64_t utime = 0;
  int64_t id = 0;  ///< frame id or keyframe id
  Transformationd T_G_C;
};

/// What a replay did. Plain value type.
struct ReplaySummary {
  uint64_t events = 0;
  uint64_t tracker_frames = 0;  ///< frames handed to the tracker
  uint64_t depth_frames = 0;    ///< depth frames handed to the mapper
  uint64_t ground_truth_poses = 0;
  /// Events of channels the replay does not use (e.g. a recorded tracker's outputs), by
  /// channel.
  std::map<std::string, uint64_t> ignored;
  /// Stretches of the log that did not read as events (a damaged event, or the end of a log
  /// cut short when the logger was killed), skipped to the next event, and their bytes.
  uint64_t damaged_regions = 0;
  uint64_t skipped_bytes = 0;
  bool stopped = false;  ///< the stop flag ended it before the end of the log
  /// Messages the tracker's and the mapper's message guards refused, by WireError kind
  /// (wireErrorName), e.g. fingerprint_mismatch for a log of another message version; and
  /// handler errors.
  std::map<std::string, uint64_t> refused;
  uint64_t handler_errors = 0;
  double wall_s = 0.0;
  double log_span_s = 0.0;  ///< time stamps of the first to the last event
  /// Frame poses the tracker published with a pose, in order (tracker mode).
  std::vector<ReplayPose> frame_poses;
  /// Every keyframe at its final pose (after the last pose batch), by map epoch and id
  /// (tracker mode).
  std::vector<ReplayPose> keyframes;
  TrackerStatus tracker;  ///< tracker mode
  MapperStatus mapper;
};

/// Plays an LCM log into a TrackerNode and a Mapper connected, as cblox-tracker and
/// cblox-mapper are, through their own LCM adapters (TrackerLcmNode, MapperNode), but over an
/// in-process bus (memq://), so every message takes the live path: wire check, decoding,
/// input checks and the same handlers.
///
/// Determinism: the same log and settings give the same frame and keyframe poses and the
/// same map, bit for bit. Every input is handed over alone and followed by waiting until
/// every thread it started is done and every message it caused has been delivered (the
/// tracker with its local mapping, loop closing and covariance service; the mapper with its
/// integrator, maintenance and fusion threads), so no decision depends on thread timing. The
/// settings that read the wall clock are replaced: the mapper's integration time budget is
/// off, it does not wait for a pose that is not there when a frame is handed over, its
/// maintenance runs on the inputs' clock (MaintenanceClock::kInput), and the
/// tracker's covariance service linearises the map afresh for every request. Inputs are
/// reordered only as a live system would see them in time: a tracker frame is handed over
/// when the next one is read (so the ground truth published after it is there first), and a
/// depth frame when the mapper has a pose at or after its time stamp (its own frame's).
/// The log's other channels (a recorded tracker's or mapper's outputs, commands) are not
/// used (counted by channel).
///
/// Thread-safety: one run() per object, from one thread.
class LogReplayer {
 public:
  /// Throws std::invalid_argument for an invalid config. `vocabulary` may be null and must
  /// outlive the replayer.
  LogReplayer(ReplayConfig config, const BinaryVocabulary* vocabulary);
  ~LogReplayer();
  LogReplayer(const LogReplayer&) = delete;
  LogReplayer& operator=(const LogReplayer&) = delete;

  /// Plays the whole log (or until `*stop`), then waits until everything is settled and map
  /// maintenance, ticked (Mapper::maintenanceTick) as a live mapper's clock would, has asked
  /// and fused every pair that became due after the last input.
  /// `progress` is called about every `progress_period_s` of wall time and at the end.
  /// Throws std::runtime_error when the log cannot be opened or the mapper cannot start.
  ReplaySummary run(const std::function<void(const ReplayProgress&)>& progress,
                    double progress_period_s, const std::atomic<bool>* stop);

  /// A mapper command after run() (e.g. "export_mesh" {path}), answered synchronously.
  MapperReply command(const MapperCommand& command);

  /// The settings in use (after the replay's replacements).
  const ReplayConfig& config() const { return config_; }

 private:
  struct Impl;
  ReplayConfig config_;
  std::unique_ptr<Impl> impl_;
};

/// The settings a replay uses in place of `config`'s: see LogReplayer (time budget off,
/// input clock, fresh linearizations, the mapper's depth on a channel of its own).
ReplayConfig deterministicReplayConfig(ReplayConfig config);

}  // namespace cblox
