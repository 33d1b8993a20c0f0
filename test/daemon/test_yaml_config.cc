#include "daemon/common/yaml_config.h"

#include <utility>

#include <gtest/gtest.h>

namespace cblox {
namespace {

std::string errorOf(const std::function<void()>& load) {
  try {
    load();
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "";
}

TEST(YamlConfig, ShippedConfigMatchesTheCodeDefaults) {
  // config/integrate.yaml documents the defaults: loading it must give exactly them.
  const YAML::Node root = loadYamlFile(CBLOX_CONFIG_DIR "/integrate.yaml");
  const LayerConfig layer = loadLayerConfig(root["layer"]);
  EXPECT_EQ(layer.voxel_size, LayerConfig{}.voxel_size);
  EXPECT_EQ(layer.voxels_per_side, LayerConfig{}.voxels_per_side);
  IntegratorType type = IntegratorType::kSimple;
  const IntegratorConfig integrator =
      loadIntegratorConfig(root["integrator"], layer.voxel_size, &type);
  const IntegratorConfig defaults;
  EXPECT_EQ(type, IntegratorType::kFast);
  EXPECT_EQ(integrator.truncation_distance_m, defaults.truncation_distance_m);
  EXPECT_EQ(integrator.max_weight, defaults.max_weight);
  EXPECT_EQ(integrator.min_ray_length_m, defaults.min_ray_length_m);
  EXPECT_EQ(integrator.max_ray_length_m, 4.0f);  // the one deliberate difference: 7-Scenes' 4 m
  EXPECT_EQ(integrator.weight_model, defaults.weight_model);
  EXPECT_EQ(integrator.use_weight_dropoff, defaults.use_weight_dropoff);
  EXPECT_EQ(integrator.voxel_carving_enabled, defaults.voxel_carving_enabled);
  EXPECT_EQ(integrator.projective_carving_depth_m, defaults.projective_carving_depth_m);
  EXPECT_EQ(integrator.color_blending, defaults.color_blending);
  EXPECT_EQ(integrator.num_threads, defaults.num_threads);
  EXPECT_EQ(integrator.start_voxel_subsampling_factor, defaults.start_voxel_subsampling_factor);
  EXPECT_EQ(integrator.max_consecutive_ray_collisions, defaults.max_consecutive_ray_collisions);
  EXPECT_EQ(integrator.max_integration_time_s, defaults.max_integration_time_s);
  EXPECT_EQ(integrator.visited_voxel_set, defaults.visited_voxel_set);
  EXPECT_EQ(integrator.approx_set_log2_buckets, defaults.approx_set_log2_buckets);
  const MeshConfig mesh = loadMeshConfig(root["mesh"]);
  EXPECT_EQ(mesh.min_weight, MeshConfig{}.min_weight);
  EXPECT_EQ(mesh.num_threads, MeshConfig{}.num_threads);
}

TEST(YamlConfig, MissingSectionsKeepDefaults) {
  const YAML::Node empty;
  EXPECT_EQ(loadLayerConfig(empty).voxel_size, LayerConfig{}.voxel_size);
  IntegratorType type = IntegratorType::kProjective;
  EXPECT_EQ(loadIntegratorConfig(empty, 0.02f, &type).num_threads, IntegratorConfig{}.num_threads);
  EXPECT_EQ(type, IntegratorType::kProjective);
}

TEST(YamlConfig, ValuesAreRead) {
  const YAML::Node node = YAML::Load(
      "type: projective\ntruncation_distance_m: 0.1\nweight_model: constant\n"
      "color_blending: none\nnum_threads: 1\nvisited_voxel_set: hash_set\n"
      "projective_carving_depth_m: 3.0\n");
  IntegratorType type = IntegratorType::kFast;
  const IntegratorConfig config = loadIntegratorConfig(node, 0.02f, &type);
  EXPECT_EQ(type, IntegratorType::kProjective);
  EXPECT_FLOAT_EQ(config.truncation_distance_m, 0.1f);
  EXPECT_EQ(config.weight_model, WeightModel::kConstant);
  EXPECT_EQ(config.color_blending, ColorBlending::kNone);
  EXPECT_EQ(config.num_threads, 1);
  EXPECT_EQ(config.visited_voxel_set, VisitedVoxelSet::kApproxHashSet);
  EXPECT_EQ(config.projective_carving_depth_m, 3.0f);
}

TEST(YamlConfig, ErrorsNameTheKey) {
  IntegratorType type = IntegratorType::kFast;
  EXPECT_EQ(errorOf([] { loadLayerConfig(YAML::Load("voxel_size: -1")); }),
            "layer.voxel_size must be finite and > 0, got -1");
  EXPECT_NE(errorOf([] {
              loadLayerConfig(YAML::Load("voxels_per_sid: 8"));
            }).find("layer.voxels_per_sid: unknown setting"),
            std::string::npos);
  const std::pair<const char*, const char*> integrator_cases[] = {
      {"num_threads: two", "integrator.num_threads"},
      {"type: magic", "integrator.type"},
      {"weight_model: cubic", "integrator.weight_model"},
      {"truncation_distance_m: 0.001", "integrator.truncation_distance_m"},
      {"projective_carving_depth_m: -1", "integrator.projective_carving_depth_m"},
  };
  for (const auto& [yaml, key] : integrator_cases) {
    EXPECT_NE(errorOf([&] { loadIntegratorConfig(YAML::Load(yaml), 0.02f, &type); }).find(key),
              std::string::npos)
        << yaml;
  }
  EXPECT_NE(errorOf([] { loadMeshConfig(YAML::Load("- a list")); }).find("mesh: expected a map"),
            std::string::npos);
  EXPECT_NE(
      errorOf([] { loadYamlFile("/nonexistent/cblox.yaml"); }).find("/nonexistent/cblox.yaml"),
      std::string::npos);
}

}  // namespace
}  // namespace cblox
