#include "daemon/mapper/mapper_config_loader.h"

#include <gtest/gtest.h>

#include "daemon/common/yaml_config.h"

namespace cblox {
namespace {

TEST(MapperConfigTest, ShippedYamlMatchesTheCodeDefaults) {
  const MapperProcessConfig shipped =
      loadMapperConfig(loadYamlFile(std::string(CBLOX_CONFIG_DIR) + "/mapper.yaml"));
  const MapperProcessConfig defaults;
  const MapperConfig& a = shipped.mapper;
  const MapperConfig& b = defaults.mapper;
  EXPECT_EQ(a.pose_source, b.pose_source);
  EXPECT_EQ(shipped.lcm_url, defaults.lcm_url);
  EXPECT_EQ(a.output_dir, b.output_dir);
  EXPECT_EQ(shipped.depth_channel, defaults.depth_channel);
  EXPECT_EQ(shipped.ground_truth_channel, defaults.ground_truth_channel);
  EXPECT_EQ(shipped.frame_pose_channel, defaults.frame_pose_channel);
  EXPECT_EQ(shipped.keyframe_channel, defaults.keyframe_channel);
  EXPECT_EQ(shipped.keyframe_poses_channel, defaults.keyframe_poses_channel);
  EXPECT_EQ(shipped.command_channel, defaults.command_channel);
  EXPECT_EQ(shipped.command_reply_channel, defaults.command_reply_channel);
  EXPECT_EQ(shipped.map_status_channel, defaults.map_status_channel);
  EXPECT_EQ(shipped.heartbeat_channel, defaults.heartbeat_channel);
  EXPECT_EQ(shipped.covariance_request_channel, defaults.covariance_request_channel);
  EXPECT_EQ(shipped.covariance_reply_channel, defaults.covariance_reply_channel);
  EXPECT_EQ(shipped.distance_request_channel, defaults.distance_request_channel);
  EXPECT_EQ(shipped.distance_reply_channel, defaults.distance_reply_channel);
  EXPECT_EQ(shipped.local_grid_channel, defaults.local_grid_channel);
  EXPECT_EQ(a.layer.voxel_size, b.layer.voxel_size);
  EXPECT_EQ(a.layer.voxels_per_side, b.layer.voxels_per_side);
  EXPECT_EQ(a.integrator_type, b.integrator_type);
  EXPECT_EQ(a.integrator.truncation_distance_m, b.integrator.truncation_distance_m);
  EXPECT_EQ(a.integrator.max_weight, b.integrator.max_weight);
  EXPECT_EQ(a.integrator.min_ray_length_m, b.integrator.min_ray_length_m);
  EXPECT_EQ(a.integrator.max_ray_length_m, b.integrator.max_ray_length_m);
  EXPECT_EQ(a.integrator.weight_model, b.integrator.weight_model);
  EXPECT_EQ(a.integrator.use_weight_dropoff, b.integrator.use_weight_dropoff);
  EXPECT_EQ(a.integrator.projective_carving_depth_m, b.integrator.projective_carving_depth_m);
  EXPECT_EQ(a.integrator.color_blending, b.integrator.color_blending);
  EXPECT_EQ(a.integrator.num_threads, b.integrator.num_threads);
  EXPECT_EQ(a.integrator.max_integration_time_s, b.integrator.max_integration_time_s);
  EXPECT_EQ(a.mesh.min_weight, b.mesh.min_weight);
  EXPECT_EQ(a.mesh.use_color, b.mesh.use_color);
  EXPECT_EQ(a.mesh.compute_normals, b.mesh.compute_normals);
  EXPECT_EQ(a.mesh.num_threads, b.mesh.num_threads);
  EXPECT_EQ(a.fusion.max_weight, b.fusion.max_weight);
  EXPECT_EQ(a.fusion.min_weight, b.fusion.min_weight);
  EXPECT_EQ(a.fusion.min_sample_coverage, b.fusion.min_sample_coverage);
  EXPECT_EQ(a.fusion.use_color, b.fusion.use_color);
  EXPECT_EQ(a.fusion.num_threads, b.fusion.num_threads);
  EXPECT_EQ(a.maintenance.enabled, b.maintenance.enabled);
  EXPECT_EQ(a.maintenance.candidates.min_shared_landmarks,
            b.maintenance.candidates.min_shared_landmarks);
  EXPECT_EQ(a.maintenance.candidates.min_shared_ratio, b.maintenance.candidates.min_shared_ratio);
  EXPECT_EQ(a.maintenance.q_min, b.maintenance.q_min);
  EXPECT_EQ(a.maintenance.pair_keyframes, b.maintenance.pair_keyframes);
  EXPECT_EQ(a.maintenance.revisit_keyframe_gap, b.maintenance.revisit_keyframe_gap);
  EXPECT_EQ(a.maintenance.max_pairs_per_request, b.maintenance.max_pairs_per_request);
  EXPECT_EQ(a.maintenance.reply_timeout_s, b.maintenance.reply_timeout_s);
  EXPECT_EQ(a.maintenance.retry_after_s, b.maintenance.retry_after_s);
  EXPECT_EQ(a.maintenance.max_retry_after_s, b.maintenance.max_retry_after_s);
  EXPECT_EQ(a.creation.max_keyframes_per_subvolume, b.creation.max_keyframes_per_subvolume);
  EXPECT_EQ(a.creation.max_anchor_distance_m, b.creation.max_anchor_distance_m);
  EXPECT_EQ(a.creation.revisit_anchor_distance_m, b.creation.revisit_anchor_distance_m);
  EXPECT_EQ(a.creation.revisit_after_frames, b.creation.revisit_after_frames);
  EXPECT_EQ(a.creation.revisit_max_frames, b.creation.revisit_max_frames);
  EXPECT_EQ(a.keyframe_every_n_frames, b.keyframe_every_n_frames);
  EXPECT_EQ(a.pose_buffer.max_gap_s, b.pose_buffer.max_gap_s);
  EXPECT_EQ(a.pose_buffer.capacity, b.pose_buffer.capacity);
  EXPECT_EQ(a.max_pose_wait_s, b.max_pose_wait_s);
  EXPECT_EQ(a.restart_after_backwards_s, b.restart_after_backwards_s);
  EXPECT_EQ(a.pending_capacity, b.pending_capacity);
  EXPECT_EQ(a.pending_in_order, b.pending_in_order);
  EXPECT_EQ(a.maintenance_queue_capacity, b.maintenance_queue_capacity);
  EXPECT_EQ(a.command_queue_capacity, b.command_queue_capacity);
  EXPECT_EQ(a.worker_niceness, b.worker_niceness);
  EXPECT_EQ(a.worker_sched_idle, b.worker_sched_idle);
  EXPECT_EQ(shipped.status_period_s, defaults.status_period_s);
  EXPECT_EQ(shipped.progress_period_s, defaults.progress_period_s);
  EXPECT_EQ(a.timing_window, b.timing_window);
  EXPECT_EQ(a.log_interval_s, b.log_interval_s);
  EXPECT_EQ(a.checkpoint.dir, b.checkpoint.dir);
  EXPECT_EQ(a.checkpoint.period_s, b.checkpoint.period_s);
  EXPECT_EQ(a.checkpoint.resume, b.checkpoint.resume);
  EXPECT_FALSE(b.checkpoint.enabled());  // off unless configured
  EXPECT_EQ(a.integrator_niceness, b.integrator_niceness);
  EXPECT_EQ(a.memory_cap.cap_mb, b.memory_cap.cap_mb);
  EXPECT_EQ(a.memory_cap.near_only_fraction, b.memory_cap.near_only_fraction);
  EXPECT_EQ(a.memory_cap.near_distance_m, b.memory_cap.near_distance_m);
  EXPECT_TRUE(b.memory_cap.enabled());  // shipped on: never an OOM kill
  EXPECT_EQ(a.planning.enabled, b.planning.enabled);
  EXPECT_EQ(a.planning.esdf.max_distance_m, b.planning.esdf.max_distance_m);
  EXPECT_EQ(a.planning.esdf.min_weight, b.planning.esdf.min_weight);
  EXPECT_EQ(a.planning.esdf.band_blocks, b.planning.esdf.band_blocks);
  EXPECT_EQ(a.planning.esdf.surface_margin_voxels, b.planning.esdf.surface_margin_voxels);
  EXPECT_EQ(a.planning.refresh_period_s, b.planning.refresh_period_s);
  EXPECT_EQ(a.planning.service.queue_capacity, b.planning.service.queue_capacity);
  EXPECT_EQ(a.planning.service.query_threads, b.planning.service.query_threads);
  EXPECT_EQ(a.planning.service.grid_period_s, b.planning.service.grid_period_s);
  EXPECT_EQ(a.planning.service.grid_size_m, b.planning.service.grid_size_m);
  EXPECT_EQ(a.planning.service.grid_resolution_m, b.planning.service.grid_resolution_m);
  EXPECT_EQ(shipped.mesh_update_channel, defaults.mesh_update_channel);
  EXPECT_EQ(shipped.subvolumes_channel, defaults.subvolumes_channel);
  EXPECT_EQ(a.mesh_stream.enabled, b.mesh_stream.enabled);
  EXPECT_EQ(a.mesh_stream.period_s, b.mesh_stream.period_s);
  EXPECT_EQ(a.mesh_stream.max_bytes_per_period, b.mesh_stream.max_bytes_per_period);
  EXPECT_EQ(a.mesh_stream.max_message_bytes, b.mesh_stream.max_message_bytes);
  EXPECT_EQ(a.mesh_stream.refresh_period_s, b.mesh_stream.refresh_period_s);
  EXPECT_EQ(a.mesh_stream.use_color, b.mesh_stream.use_color);
  EXPECT_TRUE(defaults.validate().empty()) << defaults.validate();
}

// The street example sets what it says and keeps the other defaults.
TEST(MapperConfigTest, StreetExampleLoads) {
  const MapperProcessConfig street = loadMapperConfig(
      loadYamlFile(std::string(CBLOX_CONFIG_DIR) + "/examples/mapper_street.yaml"));
  EXPECT_EQ(street.mapper.layer.voxel_size, 0.2f);
  EXPECT_EQ(street.mapper.integrator.truncation_distance_m, 0.6f);
  EXPECT_EQ(street.mapper.integrator.max_ray_length_m, 30.0f);
  EXPECT_EQ(street.mapper.layer.voxels_per_side, MapperProcessConfig{}.mapper.layer.voxels_per_side);
}

TEST(MapperConfigTest, IntegratorNicenessAndMemoryCapAreRead) {
  const MapperProcessConfig config = loadMapperConfig(
      YAML::Load("integrator: {niceness: 7}\nmemory: {cap_mb: 0, near_only_fraction: 0.5, "
                 "near_distance_m: 3.0}\n"));
  EXPECT_EQ(config.mapper.integrator_niceness, 7);
  EXPECT_EQ(config.mapper.integrator.truncation_distance_m, 0.12f);  // the rest as before
  EXPECT_FALSE(config.mapper.memory_cap.enabled());
  EXPECT_EQ(config.mapper.memory_cap.near_only_fraction, 0.5);
  EXPECT_EQ(config.mapper.memory_cap.near_distance_m, 3.0f);
  EXPECT_THROW(loadMapperConfig(YAML::Load("integrator: {niceness: 25}\n")), ConfigError);
  EXPECT_THROW(loadMapperConfig(YAML::Load("memory: {near_only_fraction: 1.5}\n")), ConfigError);
  EXPECT_THROW(loadMapperConfig(YAML::Load("memory: {cap: 5}\n")), ConfigError);
}

TEST(MapperConfigTest, AbsentKeysKeepTheMapperDefaultsNotTheGenericOnes) {
  const MapperProcessConfig config =
      loadMapperConfig(YAML::Load("integrator: {type: fast}\nlayer: {voxels_per_side: 16}\n"));
  EXPECT_EQ(config.mapper.integrator_type, IntegratorType::kFast);
  EXPECT_EQ(config.mapper.layer.voxel_size, 0.04f);
  EXPECT_EQ(config.mapper.layer.voxels_per_side, 16);
  EXPECT_EQ(config.mapper.integrator.truncation_distance_m, 0.12f);
  EXPECT_EQ(config.mapper.integrator.num_threads, 1);
  const MapperProcessConfig empty = loadMapperConfig(YAML::Load(""));
  EXPECT_EQ(empty.mapper.layer.voxel_size, 0.04f);
}

TEST(MapperConfigTest, ReadsOverrides) {
  const MapperProcessConfig config = loadMapperConfig(YAML::Load(
      "pose_source: tracker\noutput_dir: /data/maps\nlcm_url: udpm://x\n"
      "channels: {depth: D, command: C, covariance_request: REQ, covariance_reply: REP}\n"
      "layer: {voxel_size: 0.02}\n"
      "integrator: {truncation_distance_m: 0.08, num_threads: 2}\n"
      "subvolumes: {max_keyframes_per_subvolume: 5, max_anchor_distance_m: 4.5, "
      "revisit_anchor_distance_m: 0.75, revisit_after_frames: 7, revisit_max_frames: 9, "
      "keyframe_every_n_frames: 3}\n"
      "poses: {max_gap_s: 0.1, max_wait_s: 0.2, buffer_capacity: 64, restart_after_backwards_s: "
      "0}\n"
      "queues: {pending_frames: 2, in_order: false, maintenance: 8, commands: 1}\n"
      "worker: {niceness: 19, sched_idle: false}\n"
      "status: {period_s: 0.5, progress_period_s: 2, timing_window: 10, log_interval_s: 1}\n"
      "checkpoint: {dir: /data/ckpt, period_s: 45, resume: false}\n"
      "fusion: {num_threads: 1}\nmesh: {use_color: false}\n"
      "maintenance: {enabled: false, min_shared_landmarks: 50, min_shared_ratio: 0.5, q_min: "
      "2500, pair_keyframes: most_shared_on_revisits, revisit_keyframe_gap: 12, "
      "max_pairs_per_request: 3, reply_timeout_s: 1, "
      "retry_after_s: 9, "
      "max_retry_after_s: 30}\n"));
  const MapperConfig& m = config.mapper;
  EXPECT_EQ(m.pose_source, PoseSource::kTracker);
  EXPECT_EQ(m.output_dir, "/data/maps");
  EXPECT_EQ(config.lcm_url, "udpm://x");
  EXPECT_EQ(config.depth_channel, "D");
  EXPECT_EQ(config.command_channel, "C");
  EXPECT_EQ(m.layer.voxel_size, 0.02f);
  EXPECT_EQ(m.integrator.truncation_distance_m, 0.08f);
  EXPECT_EQ(m.integrator.num_threads, 2);
  EXPECT_EQ(m.creation.max_keyframes_per_subvolume, 5);
  EXPECT_EQ(m.creation.max_anchor_distance_m, 4.5);
  EXPECT_EQ(m.creation.revisit_anchor_distance_m, 0.75);
  EXPECT_EQ(m.creation.revisit_after_frames, 7);
  EXPECT_EQ(m.creation.revisit_max_frames, 9);
  EXPECT_EQ(m.keyframe_every_n_frames, 3);
  EXPECT_EQ(m.pose_buffer.max_gap_s, 0.1);
  EXPECT_EQ(m.max_pose_wait_s, 0.2);
  EXPECT_EQ(m.pose_buffer.capacity, 64u);
  EXPECT_EQ(m.restart_after_backwards_s, 0.0);
  EXPECT_EQ(m.pending_capacity, 2u);
  EXPECT_FALSE(m.pending_in_order);
  EXPECT_EQ(m.maintenance_queue_capacity, 8u);
  EXPECT_EQ(m.command_queue_capacity, 1u);
  EXPECT_EQ(m.worker_niceness, 19);
  EXPECT_FALSE(m.worker_sched_idle);
  EXPECT_EQ(config.status_period_s, 0.5);
  EXPECT_EQ(config.progress_period_s, 2.0);
  EXPECT_EQ(m.timing_window, 10u);
  EXPECT_EQ(m.log_interval_s, 1.0);
  EXPECT_EQ(m.checkpoint.dir, "/data/ckpt");
  EXPECT_EQ(m.checkpoint.period_s, 45.0);
  EXPECT_FALSE(m.checkpoint.resume);
  EXPECT_TRUE(m.checkpoint.enabled());
  EXPECT_EQ(m.fusion.num_threads, 1);
  EXPECT_FALSE(m.mesh.use_color);
  EXPECT_FALSE(m.maintenance.enabled);
  EXPECT_EQ(m.maintenance.candidates.min_shared_landmarks, 50);
  EXPECT_EQ(m.maintenance.candidates.min_shared_ratio, 0.5);
  EXPECT_EQ(m.maintenance.q_min, 2500.0);
  EXPECT_EQ(m.maintenance.pair_keyframes, PairKeyframes::kMostSharedOnRevisits);
  EXPECT_EQ(m.maintenance.revisit_keyframe_gap, 12);
  EXPECT_EQ(m.maintenance.max_pairs_per_request, 3);
  EXPECT_EQ(m.maintenance.reply_timeout_s, 1.0);
  EXPECT_EQ(m.maintenance.retry_after_s, 9.0);
  EXPECT_EQ(m.maintenance.max_retry_after_s, 30.0);
  EXPECT_EQ(config.covariance_request_channel, "REQ");
  EXPECT_EQ(config.covariance_reply_channel, "REP");
}

TEST(MapperConfigTest, ReadsThePlanningSectionAndItsChannels) {
  const MapperProcessConfig config = loadMapperConfig(YAML::Load(
      "planning: {enabled: true, max_distance_m: 1.5, min_weight: 0.01, band_blocks: 2,\n"
      "  surface_margin_voxels: 0.25, refresh_period_s: 2,\n"
      "  query_queue_capacity: 4, query_threads: 3, local_grid_period_s: 0.5,\n"
      "  local_grid_size_m: [4, 5, 1.5],\n"
      "  local_grid_resolution_m: 0.2}\n"
      "channels: {distance_request: DQ, distance_reply: DR, local_grid: LG}\n"));
  const PlanningConfig& p = config.mapper.planning;
  EXPECT_TRUE(p.enabled);
  EXPECT_EQ(p.esdf.max_distance_m, 1.5f);
  EXPECT_EQ(p.esdf.min_weight, 0.01f);
  EXPECT_EQ(p.esdf.band_blocks, 2);
  EXPECT_EQ(p.esdf.surface_margin_voxels, 0.25f);
  EXPECT_EQ(p.refresh_period_s, 2.0);
  EXPECT_EQ(p.service.queue_capacity, 4U);
  EXPECT_EQ(p.service.query_threads, 3);
  EXPECT_EQ(p.service.grid_period_s, 0.5);
  EXPECT_EQ(p.service.grid_size_m, Eigen::Vector3d(4.0, 5.0, 1.5));
  EXPECT_EQ(p.service.grid_resolution_m, 0.2);
  EXPECT_EQ(config.distance_request_channel, "DQ");
  EXPECT_EQ(config.distance_reply_channel, "DR");
  EXPECT_EQ(config.local_grid_channel, "LG");
  EXPECT_EQ(loadMapperConfig(YAML::Load("planning: {band_blocks: auto}\n"))
                .mapper.planning.esdf.band_blocks,
            PlanningConfig::kBandAuto);
}

TEST(MapperConfigTest, ReadsTheMeshStreamSectionAndItsChannels) {
  const MapperProcessConfig config = loadMapperConfig(YAML::Load(
      "mesh_stream: {enabled: false, period_s: 0.5, max_bytes_per_period: 1000000,\n"
      "  max_message_bytes: 65536, refresh_period_s: 30, use_color: false}\n"
      "channels: {mesh_update: MU, subvolumes: SV}\n"));
  const MeshStreamConfig& s = config.mapper.mesh_stream;
  EXPECT_FALSE(s.enabled);
  EXPECT_EQ(s.period_s, 0.5);
  EXPECT_EQ(s.max_bytes_per_period, 1000000u);
  EXPECT_EQ(s.max_message_bytes, 65536u);
  EXPECT_EQ(s.refresh_period_s, 30.0);
  EXPECT_FALSE(s.use_color);
  EXPECT_EQ(config.mesh_update_channel, "MU");
  EXPECT_EQ(config.subvolumes_channel, "SV");
  // 32-voxel blocks need the stream off.
  EXPECT_NO_THROW(loadMapperConfig(
      YAML::Load("layer: {voxels_per_side: 32}\nmesh_stream: {enabled: false}\n")));
}

TEST(MapperConfigTest, RejectsBadKeysAndValuesNamingThem) {
  struct Case {
    const char* yaml;
    const char* message;
  };
  const Case cases[] = {
      {"pose_sorce: tracker\n", "pose_sorce"},
      {"pose_source: slam\n", "pose_source"},
      {"channels: {dept: X}\n", "dept"},
      {"maintenance: {q_min: 0}\n", "maintenance.q_min"},
      {"maintenance: {min_shared_ratio: 1.5}\n", "maintenance.candidates.min_shared_ratio"},
      {"maintenance: {qmin: 5}\n", "qmin"},
      {"maintenance: {pair_keyframes: nearest}\n",
       "maintenance.pair_keyframes must be anchors, most_shared or most_shared_on_revisits, got "
       "'nearest'"},
      {"maintenance: {revisit_keyframe_gap: 0}\n",
       "maintenance.revisit_keyframe_gap must be >= 1, got 0"},
      {"maintenance: {max_retry_after_s: 1}\n", "maintenance.max_retry_after_s"},
      {"layer: {voxel_size: -1}\n", "voxel_size"},
      {"integrator: {truncation_distance_m: 0.01}\n", "truncation"},  // < one 4 cm voxel
      {"integrator: {type: magic}\n", "integrator.type"},
      {"subvolumes: {keyframe_every_n_frames: 0}\n", "keyframe_every_n_frames"},
      {"subvolumes: {max_keyframes_per_subvolume: 0}\n", "max_keyframes_per_subvolume"},
      {"subvolumes: {max_anchor_distance_m: -2}\n", "max_anchor_distance_m"},
      {"subvolumes: {revisit_anchor_distance_m: -1}\n", "revisit_anchor_distance_m"},
      {"subvolumes: {revisit_after_frames: -2}\n", "revisit_after_frames"},
      {"subvolumes: {revisit_max_frames: -1}\n", "revisit_max_frames"},
      {"poses: {max_gap_s: 0}\n", "max_gap_s"},
      {"poses: {max_wait_s: -1}\n", "max_pose_wait_s"},
      {"poses: {restart_after_backwards_s: -1}\n", "restart_after_backwards_s"},
      {"queues: {pending_frames: 0}\n", "pending_capacity"},
      {"worker: {niceness: 25}\n", "worker_niceness"},
      {"status: {period_s: 0}\n", "period_s"},
      {"fusion: {num_threads: 0}\n", "num_threads"},
      {"output_dir: ''\n", "output_dir"},
      {"integrator: {num_threads: two}\n", "integrator.num_threads"},
      {"checkpoint: {period_s: -1}\n", "checkpoint.period_s"},
      {"mesh_stream: {period_s: 0}\n", "mesh_stream.period_s"},
      {"mesh_stream: {max_message_bytes: 100}\n", "mesh_stream.max_message_bytes"},
      {"mesh_stream: {max_bytes_per_period: 5000}\n", "mesh_stream.max_bytes_per_period"},
      {"mesh_stream: {refresh_period_s: 0.2}\n", "mesh_stream.refresh_period_s"},
      {"mesh_stream: {colour: true}\n", "colour"},
      {"layer: {voxels_per_side: 32}\n", "needs voxels_per_side <= 16"},
      {"checkpoint: {period_s: .nan}\n", "checkpoint.period_s"},
      {"checkpoint: {period_s: .inf}\n", "checkpoint.period_s"},
      {"checkpoint: {interval_s: 5}\n", "interval_s"},
      {"checkpoint: {resume: maybe}\n", "checkpoint.resume"},
      {"planning: {max_distance_m: 0}\n", "planning."},
      {"planning: {band_blocks: 3}\n", "planning.band_blocks"},
      {"planning: {band_blocks: -1}\n", "planning.band_blocks"},
      {"planning: {surface_margin_voxels: 2}\n", "planning.surface_margin_voxels"},
      {"planning: {query_queue_capacity: -1}\n", "planning.query_queue_capacity"},
      {"planning: {query_queue_capacity: 100000}\n", "planning.query_queue_capacity"},
      {"planning: {query_threads: 0}\n", "service.query_threads"},
      {"planning: {query_threads: 17}\n", "service.query_threads"},
      {"planning: {local_grid_period_s: -1}\n", "grid_period_s"},
      {"planning: {local_grid_size_m: [1, 2]}\n", "planning.local_grid_size_m"},
      {"planning: {local_grid_size_m: [100, 100, 100]}\n", "cells"},
      {"planning: {local_grid_resolution_m: 0}\n", "grid_resolution_m"},
      {"channels: {distance_requests: X}\n", "distance_requests"},
  };
  for (const Case& c : cases) {
    try {
      loadMapperConfig(YAML::Load(c.yaml));
      ADD_FAILURE() << "accepted: " << c.yaml;
    } catch (const ConfigError& e) {
      EXPECT_NE(std::string(e.what()).find(c.message), std::string::npos)
          << c.yaml << " -> " << e.what();
    }
  }
}

}  // namespace
}  // namespace cblox
