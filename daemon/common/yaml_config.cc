#include "daemon/common/yaml_config.h"

#include <algorithm>
#include <cstring>
#include <optional>

namespace cblox {

IntegratorType parseIntegratorType(const std::string& name) {
  if (const std::optional<IntegratorType> type = integratorTypeFromName(name)) return *type;
  throw ConfigError("integrator type must be fast, simple or projective, got '" + name + "'");
}

YAML::Node loadYamlFile(const std::string& file) {
  try {
    return YAML::LoadFile(file);
  } catch (const YAML::BadFile&) {
    throw ConfigError(file + ": cannot open config file");
  } catch (const YAML::Exception& e) {
    throw ConfigError(file + ": " + e.what());
  }
}

bool isAbsent(const YAML::Node& node) { return !node || node.IsNull(); }

void requireKnownKeys(const YAML::Node& node, const std::string& path,
                      std::initializer_list<const char*> allowed) {
  if (isAbsent(node)) return;
  if (!node.IsMap()) throw ConfigError(path + ": expected a map of settings");
  for (const auto& entry : node) {
    // A map or list as a key ("{a: b}: 1") is no setting name: as<std::string>() would throw
    // YAML::TypedBadConversion, not the ConfigError (exit status 2) callers rely on.
    if (!entry.first.IsScalar()) throw ConfigError(path + ": a setting name must be plain text");
    const std::string key = entry.first.as<std::string>();
    const bool known =
        std::any_of(allowed.begin(), allowed.end(), [&](const char* a) { return key == a; });
    if (!known) throw ConfigError(path + "." + key + ": unknown setting");
  }
}

namespace {

void throwIfInvalid(const std::string& path, const std::string& error) {
  if (!error.empty()) throw ConfigError(path + "." + error);
}

}  // namespace

LayerConfig loadLayerConfig(const YAML::Node& node, const std::string& path) {
  requireKnownKeys(node, path, {"voxel_size", "voxels_per_side"});
  LayerConfig config;
  if (!isAbsent(node)) {
    readOptional(node, path, "voxel_size", &config.voxel_size);
    readOptional(node, path, "voxels_per_side", &config.voxels_per_side);
  }
  throwIfInvalid(path, config.validate());
  return config;
}

IntegratorConfig loadIntegratorConfig(const YAML::Node& node, float voxel_size,
                                      IntegratorType* type, const std::string& path) {
  requireKnownKeys(
      node, path,
      {"type", "truncation_distance_m", "max_weight", "min_ray_length_m", "max_ray_length_m",
       "weight_model", "use_weight_dropoff", "voxel_carving_enabled", "projective_carving_depth_m",
       "color_blending", "num_threads", "start_voxel_subsampling_factor",
       "max_consecutive_ray_collisions", "max_integration_time_s", "visited_voxel_set",
       "approx_set_log2_buckets"});
  IntegratorConfig config;
  if (!isAbsent(node)) {
    std::string type_name = integratorTypeName(*type);
    readOptional(node, path, "type", &type_name);
    try {
      *type = parseIntegratorType(type_name);
    } catch (const ConfigError& e) {
      throw ConfigError(path + ".type: " + e.what());
    }
    readOptional(node, path, "truncation_distance_m", &config.truncation_distance_m);
    readOptional(node, path, "max_weight", &config.max_weight);
    readOptional(node, path, "min_ray_length_m", &config.min_ray_length_m);
    readOptional(node, path, "max_ray_length_m", &config.max_ray_length_m);
    readOptionalEnum(
        node, path, "weight_model",
        {{"constant", WeightModel::kConstant}, {"inverse_square", WeightModel::kInverseSquare}},
        &config.weight_model);
    readOptional(node, path, "use_weight_dropoff", &config.use_weight_dropoff);
    readOptional(node, path, "voxel_carving_enabled", &config.voxel_carving_enabled);
    readOptional(node, path, "projective_carving_depth_m", &config.projective_carving_depth_m);
    readOptionalEnum(node, path, "color_blending",
                     {{"weighted_average", ColorBlending::kWeightedAverage},
                      {"overwrite", ColorBlending::kOverwrite},
                      {"none", ColorBlending::kNone}},
                     &config.color_blending);
    readOptional(node, path, "num_threads", &config.num_threads);
    readOptional(node, path, "start_voxel_subsampling_factor",
                 &config.start_voxel_subsampling_factor);
    readOptional(node, path, "max_consecutive_ray_collisions",
                 &config.max_consecutive_ray_collisions);
    readOptional(node, path, "max_integration_time_s", &config.max_integration_time_s);
    readOptionalEnum(node, path, "visited_voxel_set",
                     {{"block_bitmap", VisitedVoxelSet::kBlockBitmap},
                      {"hash_set", VisitedVoxelSet::kApproxHashSet}},
                     &config.visited_voxel_set);
    readOptional(node, path, "approx_set_log2_buckets", &config.approx_set_log2_buckets);
  }
  throwIfInvalid(path, config.validate(voxel_size));
  return config;
}

MeshConfig loadMeshConfig(const YAML::Node& node, const std::string& path) {
  requireKnownKeys(node, path, {"min_weight", "use_color", "compute_normals", "num_threads"});
  MeshConfig config;
  if (!isAbsent(node)) {
    readOptional(node, path, "min_weight", &config.min_weight);
    readOptional(node, path, "use_color", &config.use_color);
    readOptional(node, path, "compute_normals", &config.compute_normals);
    readOptional(node, path, "num_threads", &config.num_threads);
  }
  throwIfInvalid(path, config.validate());
  return config;
}

}  // namespace cblox
