#include "daemon/tracker/tracker_vocabulary.h"

#include <optional>
#include <utility>

#include "daemon/common/yaml_config.h"

namespace cblox {

std::string trackerVocabularyPath(const std::string& configured) {
  return configured.empty() ? std::string(CBLOX_DEFAULT_VOCABULARY) : configured;
}

std::unique_ptr<BinaryVocabulary> loadTrackerVocabulary(const std::string& configured) {
  if (configured == "none") return nullptr;
  std::string error;
  std::optional<BinaryVocabulary> vocabulary =
      BinaryVocabulary::load(trackerVocabularyPath(configured), &error);
  if (!vocabulary) {
    throw ConfigError("vocabulary: " + error +
                      (configured.empty() ? " (the build's default vocabulary; build the "
                                            "cblox_vocabulary_file target or set vocabulary)"
                                          : ""));
  }
  return std::make_unique<BinaryVocabulary>(std::move(*vocabulary));
}

}  // namespace cblox
