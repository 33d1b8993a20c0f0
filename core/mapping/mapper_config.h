#pragma once

// Settings of the dense mapper (MapperConfig): a plain value type with validate(). The
// cblox-mapper process wraps it in MapperProcessConfig (daemon/mapper/mapper_process_config.h),
// loaded from YAML by daemon/mapper/mapper_config_loader.h.

#include <climits>
#include <cstddef>
#include <cstdint>
#include <string>

#include "core/common/checkpoint_config.h"
#include "core/common/time_restart.h"
#include "core/integrator/integrator_config.h"
#include "core/integrator/make_integrator.h"
#include "core/maintenance/fusion_scheduler.h"
#include "core/mapping/memory_cap.h"
#include "core/mapping/mesh_stream_config.h"
#include "core/mapping/planning_config.h"
#include "core/mapping/pose_buffer.h"
#include "core/mesh/mesh_integrator.h"
#include "core/submap/submap_creation_policy.h"
#include "core/submap/submap_fusion.h"
#include "core/tsdf/layer_config.h"

namespace cblox {

/// Where the mapper's frame poses come from.
enum class PoseSource {
  /// Simulator / dataset ground truth (CBLOX_GT_POSE): every pose is tracked, no jumps; the
  /// mapper synthesises a keyframe every keyframe_every_n_frames integrated frames (id = the
  /// frame id, or the next unused id when a restarted source repeats frame ids; T_G_K = the
  /// frame's pose), and the first frame anchors the first subvolume.
  kGroundTruth,
  /// The tracker (CBLOX_FRAME_POSE, CBLOX_KEYFRAME, CBLOX_KEYFRAME_POSES).
  kTracker,
};
const char* poseSourceName(PoseSource source);

/// What the map maintenance's times (covariance reply timeout, retry back-off) are measured
/// on.
enum class MaintenanceClock {
  /// The computer's monotonic clock, with a 0.25 s tick that follows a timed-out request
  /// by a new one (live).
  kSteady,
  /// The inputs' time: the time stamps of accepted depth frames and poses, summed over
  /// restarts, and no tick: a request follows only a keyframe, a pose batch or a reply.
  /// With inputs given one at a time and waitUntilIdle() after each, every decision depends
  /// on the inputs alone (deterministic replay, cblox-replay).
  kInput,
};

/// Periodic incremental checkpoints of the map and resume at start (the `checkpoint` part of
/// config/mapper.yaml; README "Map file format"): core/common/checkpoint_config.h.
using MapperCheckpointConfig = CheckpointConfig;

/// Settings of a Mapper (the `mapper` part of config/mapper.yaml). Plain value type.
/// Defaults are sized for 752x480 depth at 10-20 Hz on a 2-core computer that also tracks.
struct MapperConfig {
  PoseSource pose_source = PoseSource::kGroundTruth;

  /// Subvolume geometry: 4 cm voxels, 8^3-voxel blocks (32 cm).
  LayerConfig layer{0.04f, 8};
  /// Integrator (projective by default: ~10x faster than ray casting, BENCHMARKS.md).
  IntegratorType integrator_type = IntegratorType::kProjective;
  /// Truncation 3 voxels, depth used up to 5 m, one thread (the other core is the tracker's).
  IntegratorConfig integrator = defaultIntegratorConfig();
  /// Mesh extraction for exports.
  MeshConfig mesh;
  /// Fusion of subvolumes (map maintenance, and export: projection of the collection into
  /// one volume).
  SubmapFusionConfig fusion;
  /// Map maintenance (tracker mode): covisibility candidates, covariance requests, q_min.
  FusionSchedulerConfig maintenance;
  /// The paper's subvolume creation rule.
  SubmapCreationPolicyConfig creation{10};
  /// Frame-pose buffer: interpolation gap bound and capacity.
  PoseBuffer::Config pose_buffer{0.25, 1024};

  /// Ground-truth mode: a keyframe every this many integrated frames (>= 1).
  int keyframe_every_n_frames = 10;
  /// Depth frames waiting for their pose, >= 1; when more arrive the oldest is dropped.
  size_t pending_capacity = 4;
  /// True: the waiting frames are integrated in order as their poses come (the tracker
  /// catches up after a stall and its poses then come in a burst), at most pending_capacity
  /// frames late. False: the newest frame with a pose wins and the older waiting ones are
  /// dropped (the lowest latency).
  bool pending_in_order = true;
  /// A frame newer than every pose waits at most this long for its pose, then is rejected.
  double max_pose_wait_s = 0.5;
  /// A depth frame or pose whose time stamp is this much older than the newest one means the
  /// source restarted (e.g. cblox-capture run again; simulator time starts at 0): the depth
  /// order, or the pose buffer, starts afresh (logged) instead of rejecting everything as
  /// out of order. Smaller steps back are rejected as out of order. 0 = never restart.
  double restart_after_backwards_s = 2.0;
  /// Keyframes and pose batches waiting for the maintenance thread (oldest dropped), >= 1.
  size_t maintenance_queue_capacity = 256;
  /// Export commands waiting for the worker (more are refused as busy), >= 1.
  size_t command_queue_capacity = 4;
  /// Integration times kept for the median / p99 in status, >= 1.
  size_t timing_window = 200;
  /// Exports are confined to this directory (created at start).
  std::string output_dir = "out";
  /// Niceness of the integrator thread (setpriority on its thread id), [0, 19]. Above 0, an
  /// overloaded mapper (frames integrated back to back) yields the CPU to the tracker's
  /// threads (nice 0) when both want it; with idle CPU it changes nothing.
  int integrator_niceness = 5;
  /// Niceness of the fusion/export worker thread (setpriority on its thread id), [0, 19].
  int worker_niceness = 10;
  /// Also put the worker thread in SCHED_IDLE (runs only when a core is otherwise idle).
  bool worker_sched_idle = true;
  /// Minimum interval between two log lines of the same bad-input kind, seconds (> 0).
  double log_interval_s = 10.0;
  /// Periodic checkpoints into checkpoint.dir and resume from them (off by default).
  MapperCheckpointConfig checkpoint;
  /// The cap on the map's memory and its policy (the `memory` part of config/mapper.yaml).
  /// The map's memory counts the distance fields of the planning map too.
  MemoryCapConfig memory_cap;
  /// The planning map: a distance field per subvolume, queried by planners (the `planning`
  /// part of config/mapper.yaml; planning_map.h).
  PlanningConfig planning;
  /// The incremental mesh stream for live viewers (the `mesh_stream` part of
  /// config/mapper.yaml; mesh_streamer.h). With it enabled, layer.voxels_per_side is at most
  /// 16 (a block's mesh is sent with 16-bit vertex indices).
  MeshStreamConfig mesh_stream;
  /// The clock of map maintenance (kInput for deterministic replay; not a YAML key).
  MaintenanceClock maintenance_clock = MaintenanceClock::kSteady;

  /// The default IntegratorConfig of the mapper (see `integrator`).
  static IntegratorConfig defaultIntegratorConfig();
  /// Empty when valid, otherwise a message naming the offending field. Thread-safe.
  std::string validate() const;
};

}  // namespace cblox
