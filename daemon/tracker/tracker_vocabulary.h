#pragma once

// The place-recognition vocabulary a tracker config names, loaded (cblox-tracker and
// cblox-replay).

#include <memory>
#include <string>

#include "core/vocabulary/binary_vocabulary.h"

namespace cblox {

/// The path a TrackerProcessConfig::vocabulary value means: empty = the build's default
/// vocabulary (CBLOX_DEFAULT_VOCABULARY), anything else itself. Thread-safe (pure).
std::string trackerVocabularyPath(const std::string& configured);

/// Loads the vocabulary `configured` names; "none" gives null (no relocalization, no loop
/// closing). Throws ConfigError naming the file and the problem. Thread-safe.
std::unique_ptr<BinaryVocabulary> loadTrackerVocabulary(const std::string& configured);

}  // namespace cblox
