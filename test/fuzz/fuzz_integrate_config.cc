// Fuzz target: config/integrate.yaml as cblox-integrate reads it (daemon/tools/
// cblox_integrate.cc: loadYamlFile, the known top-level keys, then the layer, integrator and
// mesh sections with daemon/common/yaml_config.h's loaders, each validating its config), on
// any bytes. (Its `synthetic` and `output` sections are read in the tool's own main.) The tool
// turns ConfigError into exit status 2; anything else escapes as a crash.

#include <cstddef>
#include <cstdint>
#include <string>

#include <yaml-cpp/yaml.h>

#include "daemon/common/yaml_config.h"
#include "test/fuzz/support/fuzz_files.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string& dir = cblox::fuzz::freshScratchDir();
  cblox::fuzz::writeScratchFile(dir, "integrate.yaml", {reinterpret_cast<const char*>(data), size});
  try {
    const YAML::Node root = cblox::loadYamlFile(dir + "/integrate.yaml");
    cblox::requireKnownKeys(root, "config", {"layer", "integrator", "mesh", "output", "synthetic"});
    const cblox::LayerConfig layer = cblox::loadLayerConfig(root["layer"]);
    cblox::IntegratorType type = cblox::IntegratorType::kFast;
    (void)cblox::loadIntegratorConfig(root["integrator"], layer.voxel_size, &type);
    (void)cblox::loadMeshConfig(root["mesh"]);
  } catch (const cblox::ConfigError&) {
  }
  return 0;
}
