#pragma once

// A command to the mapper (from command_t on CBLOX_CMD) and its answer (command_reply_t).

#include <cstdint>
#include <map>
#include <string>
#include <utility>
#include <vector>

namespace cblox {

/// A command (from command_t). Plain value type.
struct MapperCommand {
  int64_t id = 0;
  std::string name;  ///< "status", "export_mesh", "export_submap_meshes", "save_map", "load_map"
  std::map<std::string, std::string> args;
};

/// The answer to a command (to command_reply_t). Plain value type.
struct MapperReply {
  int64_t id = 0;
  bool ok = false;
  std::string message;
  std::vector<std::pair<std::string, std::string>> values;
  /// The value of `key`, empty when absent. Thread-safe (const).
  std::string value(const std::string& key) const;
};

}  // namespace cblox
