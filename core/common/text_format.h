#pragma once

// Small formatting and timing helpers of the daemons' log lines and replies.

#include <chrono>
#include <cstdio>
#include <string>

namespace cblox {

/// `value` with `decimals` digits after the point, e.g. fixed(0.1234, 3) = "0.123".
inline std::string fixed(double value, int decimals) {
  char text[64];
  std::snprintf(text, sizeof(text), "%.*f", decimals, value);
  return text;
}

/// `value` with `digits` significant digits ("%.*g"), e.g. significant(1e15, 3) = "1e+15",
/// significant(4194304, 3) = "4.19e+06": counts too large to read exactly.
inline std::string significant(double value, int digits) {
  char text[64];
  std::snprintf(text, sizeof(text), "%.*g", digits, value);
  return text;
}

/// Seconds on the steady clock since `start`.
inline double secondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace cblox
