#pragma once

// YAML -> component Config structs. Lives in daemon/ (core/ knows no YAML).
// Every loader rejects unknown keys and wrongly typed values with a message naming the
// full key path (e.g. "integrator.num_threads: expected an integer, got 'two'"), then
// runs the component's own validate().

#include <initializer_list>
#include <stdexcept>
#include <string>
#include <utility>

#include <yaml-cpp/yaml.h>

#include "core/integrator/integrator_config.h"
#include "core/integrator/make_integrator.h"
#include "core/mesh/mesh_integrator.h"
#include "core/tsdf/layer_config.h"

namespace cblox {

/// Thrown on any configuration error; what() names the key.
class ConfigError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// The integrator named `name` (integratorTypeFromName); throws ConfigError otherwise.
IntegratorType parseIntegratorType(const std::string& name);

/// Each loader starts from the struct's defaults and overrides the keys present in
/// `node` (a map; a missing node keeps all defaults). `path` prefixes error messages.
LayerConfig loadLayerConfig(const YAML::Node& node, const std::string& path = "layer");
IntegratorConfig loadIntegratorConfig(const YAML::Node& node, float voxel_size,
                                      IntegratorType* type, const std::string& path = "integrator");
MeshConfig loadMeshConfig(const YAML::Node& node, const std::string& path = "mesh");

/// Loads a YAML file; throws ConfigError with the file name on read or parse errors.
YAML::Node loadYamlFile(const std::string& file);

/// True for a missing node and for an empty (null) one, e.g. `mesh:` with no settings.
bool isAbsent(const YAML::Node& node);

/// Throws ConfigError when `node` (a map) has a key not in `allowed`.
void requireKnownKeys(const YAML::Node& node, const std::string& path,
                      std::initializer_list<const char*> allowed);

/// Reads node[key] into *value when present; throws ConfigError naming path.key when the
/// value has the wrong type.
template <typename T>
void readOptional(const YAML::Node& node, const std::string& path, const char* key, T* value) {
  const YAML::Node child = node[key];
  if (!child) return;
  try {
    *value = child.as<T>();
  } catch (const YAML::Exception&) {
    throw ConfigError(path + "." + key + ": cannot read '" + YAML::Dump(child) +
                      "' as the expected type");
  }
}

/// Reads node[key], a name from `names`, into *value when present; throws ConfigError
/// naming path.key and the accepted names otherwise.
template <typename Enum>
void readOptionalEnum(const YAML::Node& node, const std::string& path, const char* key,
                      std::initializer_list<std::pair<const char*, Enum>> names, Enum* value) {
  if (!node[key]) return;
  std::string name;
  readOptional(node, path, key, &name);
  std::string accepted;
  for (const auto& [candidate, candidate_value] : names) {
    if (name == candidate) {
      *value = candidate_value;
      return;
    }
    accepted += (accepted.empty() ? "" : ", ") + std::string(candidate);
  }
  throw ConfigError(path + "." + key + ": must be one of " + accepted + ", got '" + name + "'");
}

}  // namespace cblox
