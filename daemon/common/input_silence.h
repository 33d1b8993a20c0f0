#pragma once

// The `input_silence_s` setting of every process's YAML (capture, tracker, mapper): how long
// an input may stay silent before the heartbeat says so (daemon/common/input_watch.h).
// Header-only so that the config loaders need no LCM library.

#include <cmath>
#include <string>

namespace cblox {

/// Default of input_silence_s, seconds (0 = off).
inline constexpr double kDefaultInputSilenceS = 2.0;

/// Empty when `input_silence_s` is a valid setting (finite and >= 0; 0 = off), otherwise a
/// message naming the key. Thread-safe.
inline std::string validateInputSilence(double input_silence_s) {
  if (!std::isfinite(input_silence_s) || input_silence_s < 0.0) {
    return "input_silence_s must be finite and >= 0 (0 = off), got " +
           std::to_string(input_silence_s);
  }
  return {};
}

}  // namespace cblox
