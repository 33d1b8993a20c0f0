#include "daemon/mapper/mapper_config_loader.h"

#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "daemon/common/input_silence.h"
#include "daemon/common/yaml_config.h"

namespace cblox {
namespace {

bool present(const YAML::Node& node, const char* key) { return !isAbsent(node) && node[key]; }

// The shared loaders start from the components' defaults; the mapper's defaults differ for a
// few keys (4 cm voxels, 12 cm truncation, 5 m rays, one integration thread, 80 ms budget): keys
// absent from the file keep the mapper's values.
LayerConfig loadMapperLayer(const YAML::Node& node, const LayerConfig& defaults) {
  LayerConfig layer = loadLayerConfig(node, "layer");
  if (!present(node, "voxel_size")) layer.voxel_size = defaults.voxel_size;
  if (!present(node, "voxels_per_side")) layer.voxels_per_side = defaults.voxels_per_side;
  if (const std::string e = layer.validate(); !e.empty()) throw ConfigError("layer." + e);
  return layer;
}

IntegratorConfig loadMapperIntegrator(const YAML::Node& node, float voxel_size,
                                      const IntegratorConfig& defaults, IntegratorType* type,
                                      int* niceness) {
  // Validate against the mapper's defaults for the absent keys, not the generic ones.
  YAML::Node merged = isAbsent(node) ? YAML::Node(YAML::NodeType::Map) : YAML::Clone(node);
  // The integrator thread's niceness is the mapper's, not the integrator's.
  readOptional(merged, "integrator", "niceness", niceness);
  merged.remove("niceness");
  if (!merged["truncation_distance_m"])
    merged["truncation_distance_m"] = defaults.truncation_distance_m;
  if (!merged["max_ray_length_m"]) merged["max_ray_length_m"] = defaults.max_ray_length_m;
  if (!merged["num_threads"]) merged["num_threads"] = defaults.num_threads;
  if (!merged["max_integration_time_s"]) {
    merged["max_integration_time_s"] = defaults.max_integration_time_s;
  }
  return loadIntegratorConfig(merged, voxel_size, type, "integrator");
}

SubmapFusionConfig loadFusion(const YAML::Node& node) {
  const std::string path = "fusion";
  requireKnownKeys(node, path,
                   {"max_weight", "min_weight", "min_sample_coverage", "use_color", "num_threads"});
  SubmapFusionConfig fusion;
  if (!isAbsent(node)) {
    readOptional(node, path, "max_weight", &fusion.max_weight);
    readOptional(node, path, "min_weight", &fusion.min_weight);
    readOptional(node, path, "min_sample_coverage", &fusion.min_sample_coverage);
    readOptional(node, path, "use_color", &fusion.use_color);
    readOptional(node, path, "num_threads", &fusion.num_threads);
  }
  if (const std::string e = fusion.validate(); !e.empty()) throw ConfigError(path + "." + e);
  return fusion;
}

FusionSchedulerConfig loadMaintenance(const YAML::Node& node) {
  const std::string path = "maintenance";
  requireKnownKeys(node, path,
                   {"enabled", "min_shared_landmarks", "min_shared_ratio", "q_min",
                    "pair_keyframes", "revisit_keyframe_gap", "max_pairs_per_request",
                    "reply_timeout_s", "retry_after_s", "max_retry_after_s"});
  FusionSchedulerConfig m;
  if (!isAbsent(node)) {
    readOptional(node, path, "enabled", &m.enabled);
    readOptional(node, path, "min_shared_landmarks", &m.candidates.min_shared_landmarks);
    readOptional(node, path, "min_shared_ratio", &m.candidates.min_shared_ratio);
    readOptional(node, path, "q_min", &m.q_min);
    std::string pair_keyframes = pairKeyframesName(m.pair_keyframes);
    readOptional(node, path, "pair_keyframes", &pair_keyframes);
    if (!parsePairKeyframes(pair_keyframes, &m.pair_keyframes)) {
      throw ConfigError(path +
                        ".pair_keyframes must be anchors, most_shared or most_shared_on_revisits, "
                        "got '" +
                        pair_keyframes + "'");
    }
    readOptional(node, path, "revisit_keyframe_gap", &m.revisit_keyframe_gap);
    readOptional(node, path, "max_pairs_per_request", &m.max_pairs_per_request);
    readOptional(node, path, "reply_timeout_s", &m.reply_timeout_s);
    readOptional(node, path, "retry_after_s", &m.retry_after_s);
    readOptional(node, path, "max_retry_after_s", &m.max_retry_after_s);
  }
  if (const std::string e = m.validate(); !e.empty()) throw ConfigError(path + "." + e);
  return m;
}

}  // namespace

PoseSource parsePoseSource(const std::string& name) {
  if (name == "ground_truth") return PoseSource::kGroundTruth;
  if (name == "tracker") return PoseSource::kTracker;
  throw ConfigError("pose_source must be ground_truth or tracker, got '" + name + "'");
}

MapperProcessConfig loadMapperConfig(const YAML::Node& root) {
  MapperProcessConfig config;
  MapperConfig& m = config.mapper;
  const std::string top = "mapper";
  requireKnownKeys(root, top,
                   {"pose_source", "lcm_url", "output_dir", "input_silence_s", "channels", "layer",
                    "integrator", "mesh", "fusion", "maintenance", "subvolumes", "poses", "queues",
                    "worker", "status", "checkpoint", "memory", "planning", "mesh_stream"});
  if (isAbsent(root)) return config;

  if (root["pose_source"]) {
    std::string name;
    readOptional(root, top, "pose_source", &name);
    try {
      m.pose_source = parsePoseSource(name);
    } catch (const ConfigError& e) {
      throw ConfigError(top + "." + e.what());
    }
  }
  readOptional(root, top, "lcm_url", &config.lcm_url);
  readOptional(root, top, "output_dir", &m.output_dir);
  readOptional(root, top, "input_silence_s", &config.input_silence_s);
  if (const std::string e = validateInputSilence(config.input_silence_s); !e.empty()) {
    throw ConfigError(top + "." + e);
  }

  const YAML::Node channels = root["channels"];
  requireKnownKeys(
      channels, "channels",
      {"depth", "ground_truth_pose", "frame_pose", "keyframe", "keyframe_poses", "command",
       "command_reply", "map_status", "heartbeat", "covariance_request", "covariance_reply",
       "distance_request", "distance_reply", "local_grid", "mesh_update", "subvolumes"});
  if (!isAbsent(channels)) {
    readOptional(channels, "channels", "depth", &config.depth_channel);
    readOptional(channels, "channels", "ground_truth_pose", &config.ground_truth_channel);
    readOptional(channels, "channels", "frame_pose", &config.frame_pose_channel);
    readOptional(channels, "channels", "keyframe", &config.keyframe_channel);
    readOptional(channels, "channels", "keyframe_poses", &config.keyframe_poses_channel);
    readOptional(channels, "channels", "command", &config.command_channel);
    readOptional(channels, "channels", "command_reply", &config.command_reply_channel);
    readOptional(channels, "channels", "map_status", &config.map_status_channel);
    readOptional(channels, "channels", "heartbeat", &config.heartbeat_channel);
    readOptional(channels, "channels", "covariance_request", &config.covariance_request_channel);
    readOptional(channels, "channels", "covariance_reply", &config.covariance_reply_channel);
    readOptional(channels, "channels", "distance_request", &config.distance_request_channel);
    readOptional(channels, "channels", "distance_reply", &config.distance_reply_channel);
    readOptional(channels, "channels", "local_grid", &config.local_grid_channel);
    readOptional(channels, "channels", "mesh_update", &config.mesh_update_channel);
    readOptional(channels, "channels", "subvolumes", &config.subvolumes_channel);
  }

  m.layer = loadMapperLayer(root["layer"], m.layer);
  m.integrator = loadMapperIntegrator(root["integrator"], m.layer.voxel_size, m.integrator,
                                      &m.integrator_type, &m.integrator_niceness);
  m.mesh = loadMeshConfig(root["mesh"], "mesh");
  m.fusion = loadFusion(root["fusion"]);
  m.maintenance = loadMaintenance(root["maintenance"]);

  const YAML::Node subvolumes = root["subvolumes"];
  requireKnownKeys(
      subvolumes, "subvolumes",
      {"max_keyframes_per_subvolume", "max_anchor_distance_m", "revisit_anchor_distance_m",
       "revisit_after_frames", "revisit_max_frames", "keyframe_every_n_frames"});
  if (!isAbsent(subvolumes)) {
    readOptional(subvolumes, "subvolumes", "max_keyframes_per_subvolume",
                 &m.creation.max_keyframes_per_subvolume);
    readOptional(subvolumes, "subvolumes", "max_anchor_distance_m",
                 &m.creation.max_anchor_distance_m);
    readOptional(subvolumes, "subvolumes", "revisit_anchor_distance_m",
                 &m.creation.revisit_anchor_distance_m);
    readOptional(subvolumes, "subvolumes", "revisit_after_frames",
                 &m.creation.revisit_after_frames);
    readOptional(subvolumes, "subvolumes", "revisit_max_frames", &m.creation.revisit_max_frames);
    readOptional(subvolumes, "subvolumes", "keyframe_every_n_frames", &m.keyframe_every_n_frames);
  }

  const YAML::Node poses = root["poses"];
  requireKnownKeys(poses, "poses",
                   {"max_gap_s", "buffer_capacity", "max_wait_s", "restart_after_backwards_s"});
  if (!isAbsent(poses)) {
    readOptional(poses, "poses", "max_gap_s", &m.pose_buffer.max_gap_s);
    readOptional(poses, "poses", "buffer_capacity", &m.pose_buffer.capacity);
    readOptional(poses, "poses", "max_wait_s", &m.max_pose_wait_s);
    readOptional(poses, "poses", "restart_after_backwards_s", &m.restart_after_backwards_s);
  }

  const YAML::Node queues = root["queues"];
  requireKnownKeys(queues, "queues", {"pending_frames", "in_order", "maintenance", "commands"});
  if (!isAbsent(queues)) {
    readOptional(queues, "queues", "pending_frames", &m.pending_capacity);
    readOptional(queues, "queues", "in_order", &m.pending_in_order);
    readOptional(queues, "queues", "maintenance", &m.maintenance_queue_capacity);
    readOptional(queues, "queues", "commands", &m.command_queue_capacity);
  }

  const YAML::Node worker = root["worker"];
  requireKnownKeys(worker, "worker", {"niceness", "sched_idle"});
  if (!isAbsent(worker)) {
    readOptional(worker, "worker", "niceness", &m.worker_niceness);
    readOptional(worker, "worker", "sched_idle", &m.worker_sched_idle);
  }

  const YAML::Node status = root["status"];
  requireKnownKeys(status, "status",
                   {"period_s", "progress_period_s", "timing_window", "log_interval_s"});
  if (!isAbsent(status)) {
    readOptional(status, "status", "period_s", &config.status_period_s);
    readOptional(status, "status", "progress_period_s", &config.progress_period_s);
    readOptional(status, "status", "timing_window", &m.timing_window);
    readOptional(status, "status", "log_interval_s", &m.log_interval_s);
  }

  const YAML::Node checkpoint = root["checkpoint"];
  requireKnownKeys(checkpoint, "checkpoint", {"dir", "period_s", "resume"});
  if (!isAbsent(checkpoint)) {
    readOptional(checkpoint, "checkpoint", "dir", &m.checkpoint.dir);
    readOptional(checkpoint, "checkpoint", "period_s", &m.checkpoint.period_s);
    readOptional(checkpoint, "checkpoint", "resume", &m.checkpoint.resume);
  }

  const YAML::Node memory = root["memory"];
  requireKnownKeys(memory, "memory", {"cap_mb", "near_only_fraction", "near_distance_m"});
  if (!isAbsent(memory)) {
    readOptional(memory, "memory", "cap_mb", &m.memory_cap.cap_mb);
    readOptional(memory, "memory", "near_only_fraction", &m.memory_cap.near_only_fraction);
    readOptional(memory, "memory", "near_distance_m", &m.memory_cap.near_distance_m);
  }

  const YAML::Node planning = root["planning"];
  requireKnownKeys(
      planning, "planning",
      {"enabled", "max_distance_m", "min_weight", "band_blocks", "surface_margin_voxels",
       "refresh_period_s", "query_queue_capacity", "query_threads", "local_grid_period_s",
       "local_grid_size_m", "local_grid_resolution_m"});
  if (!isAbsent(planning)) {
    readOptional(planning, "planning", "enabled", &m.planning.enabled);
    readOptional(planning, "planning", "max_distance_m", &m.planning.esdf.max_distance_m);
    readOptional(planning, "planning", "min_weight", &m.planning.esdf.min_weight);
    if (planning["band_blocks"]) {
      std::string band;
      readOptional(planning, "planning", "band_blocks", &band);
      if (band == "auto") {
        m.planning.esdf.band_blocks = PlanningConfig::kBandAuto;
      } else if (band == "0" || band == "1" || band == "2") {
        m.planning.esdf.band_blocks = band[0] - '0';
      } else {
        throw ConfigError("planning.band_blocks: must be auto, 0, 1 or 2, got '" + band + "'");
      }
    }
    readOptional(planning, "planning", "surface_margin_voxels",
                 &m.planning.esdf.surface_margin_voxels);
    readOptional(planning, "planning", "refresh_period_s", &m.planning.refresh_period_s);
    PlanningServiceConfig& service = m.planning.service;
    if (planning["query_queue_capacity"]) {
      int64_t capacity = 0;
      readOptional(planning, "planning", "query_queue_capacity", &capacity);
      if (capacity < 1 || capacity > 1024) {
        throw ConfigError("planning.query_queue_capacity: must be in [1, 1024], got " +
                          std::to_string(capacity));
      }
      service.queue_capacity = static_cast<size_t>(capacity);
    }
    readOptional(planning, "planning", "query_threads", &service.query_threads);
    readOptional(planning, "planning", "local_grid_period_s", &service.grid_period_s);
    readOptional(planning, "planning", "local_grid_resolution_m", &service.grid_resolution_m);
    if (planning["local_grid_size_m"]) {
      std::vector<double> size;
      readOptional(planning, "planning", "local_grid_size_m", &size);
      if (size.size() != 3) {
        throw ConfigError("planning.local_grid_size_m: needs 3 numbers (x, y, z edge "
                          "lengths in metres)");
      }
      service.grid_size_m = Eigen::Vector3d(size[0], size[1], size[2]);
    }
  }

  const YAML::Node stream = root["mesh_stream"];
  requireKnownKeys(stream, "mesh_stream",
                   {"enabled", "period_s", "max_bytes_per_period", "max_message_bytes",
                    "refresh_period_s", "use_color"});
  if (!isAbsent(stream)) {
    MeshStreamConfig& s = m.mesh_stream;
    readOptional(stream, "mesh_stream", "enabled", &s.enabled);
    readOptional(stream, "mesh_stream", "period_s", &s.period_s);
    readOptional(stream, "mesh_stream", "max_bytes_per_period", &s.max_bytes_per_period);
    readOptional(stream, "mesh_stream", "max_message_bytes", &s.max_message_bytes);
    readOptional(stream, "mesh_stream", "refresh_period_s", &s.refresh_period_s);
    readOptional(stream, "mesh_stream", "use_color", &s.use_color);
  }

  if (const std::string e = config.validate(); !e.empty()) throw ConfigError(top + ": " + e);
  return config;
}

}  // namespace cblox
