#pragma once

// config/mapper.yaml -> MapperProcessConfig (YAML stays in the loaders).

#include <string>

#include <yaml-cpp/yaml.h>

#include "daemon/mapper/mapper_process_config.h"

namespace cblox {

/// Parses "ground_truth" / "tracker"; throws ConfigError otherwise. Thread-safe.
PoseSource parsePoseSource(const std::string& name);

/// Reads the YAML tree of config/mapper.yaml over the defaults (absent keys keep the code's
/// defaults, including the mapper's own layer and integrator defaults); throws ConfigError
/// naming the key for unknown keys or bad values. Thread-safe.
MapperProcessConfig loadMapperConfig(const YAML::Node& root);

}  // namespace cblox
