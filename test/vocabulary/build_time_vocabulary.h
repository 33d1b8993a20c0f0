#pragma once

#include <filesystem>
#include <optional>
#include <string>

#include "core/vocabulary/binary_vocabulary.h"

namespace cblox::test {

/// The vocabulary trained at build time (CBLOX_DEFAULT_VOCABULARY, daemon/CMakeLists.txt).
struct BuildTimeVocabulary {
  std::optional<BinaryVocabulary> vocabulary;
  std::string skip_reason;  ///< set when it was not built (tests skip)
  std::string error;        ///< set when it exists but does not load (tests fail)
};

inline BuildTimeVocabulary loadBuildTimeVocabulary() {
  BuildTimeVocabulary result;
#ifndef CBLOX_DEFAULT_VOCABULARY
  result.skip_reason = "no build-time vocabulary (test built without cblox_default_vocabulary)";
#else
  if (!std::filesystem::exists(CBLOX_DEFAULT_VOCABULARY)) {
    result.skip_reason = std::string("no build-time vocabulary at ") + CBLOX_DEFAULT_VOCABULARY +
                         " (CBLOX_BUILD_VOCABULARY=OFF?)";
  } else {
    result.vocabulary = BinaryVocabulary::load(CBLOX_DEFAULT_VOCABULARY, &result.error);
  }
#endif
  return result;
}

}  // namespace cblox::test
