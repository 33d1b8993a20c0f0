#include "core/mapping/mapper_config.h"

#include <cmath>

namespace cblox {

const char* poseSourceName(PoseSource source) {
  return source == PoseSource::kGroundTruth ? "ground_truth" : "tracker";
}

IntegratorConfig MapperConfig::defaultIntegratorConfig() {
  IntegratorConfig config;
  config.truncation_distance_m = 0.12f;  // 3 voxels of 4 cm
  config.max_ray_length_m = 5.0f;
  config.num_threads = 1;
  config.max_integration_time_s = 0.08;  // per frame: keeps up at 10 Hz beside the tracker
  return config;
}

std::string MapperConfig::validate() const {
  if (std::string e = layer.validate(); !e.empty()) return "layer." + e;
  if (std::string e = integrator.validate(layer.voxel_size); !e.empty()) return "integrator." + e;
  if (std::string e = mesh.validate(); !e.empty()) return "mesh." + e;
  if (std::string e = fusion.validate(); !e.empty()) return "fusion." + e;
  if (std::string e = maintenance.validate(); !e.empty()) return "maintenance." + e;
  if (std::string e = creation.validate(); !e.empty()) return "creation." + e;
  if (std::string e = pose_buffer.validate(); !e.empty()) return "pose_buffer." + e;
  if (keyframe_every_n_frames < 1) {
    return "keyframe_every_n_frames must be >= 1, got " + std::to_string(keyframe_every_n_frames);
  }
  if (pending_capacity < 1) return "pending_capacity must be >= 1";
  if (!(max_pose_wait_s >= 0.0) || !std::isfinite(max_pose_wait_s)) {
    return "max_pose_wait_s must be finite and >= 0, got " + std::to_string(max_pose_wait_s);
  }
  if (!(restart_after_backwards_s >= 0.0) || !std::isfinite(restart_after_backwards_s)) {
    return "restart_after_backwards_s must be finite and >= 0, got " +
           std::to_string(restart_after_backwards_s);
  }
  if (maintenance_queue_capacity < 1) return "maintenance_queue_capacity must be >= 1";
  if (command_queue_capacity < 1) return "command_queue_capacity must be >= 1";
  if (timing_window < 1) return "timing_window must be >= 1";
  if (output_dir.empty()) return "output_dir must not be empty";
  if (integrator_niceness < 0 || integrator_niceness > 19) {
    return "integrator_niceness must be in [0, 19], got " + std::to_string(integrator_niceness);
  }
  if (worker_niceness < 0 || worker_niceness > 19) {
    return "worker_niceness must be in [0, 19], got " + std::to_string(worker_niceness);
  }
  if (!(log_interval_s > 0.0) || !std::isfinite(log_interval_s)) {
    return "log_interval_s must be finite and > 0, got " + std::to_string(log_interval_s);
  }
  if (std::string e = checkpoint.validate(); !e.empty()) return "checkpoint." + e;
  if (std::string e = memory_cap.validate(); !e.empty()) return "memory." + e;
  if (std::string e = planning.validate(); !e.empty()) return e;
  if (std::string e = mesh_stream.validate(); !e.empty()) return "mesh_stream." + e;
  if (mesh_stream.enabled && layer.voxels_per_side > 16) {
    return "mesh_stream.enabled needs voxels_per_side <= 16 (a block's mesh is sent with 16-bit "
           "vertex indices), got " + std::to_string(layer.voxels_per_side);
  }
  return {};
}

}  // namespace cblox
