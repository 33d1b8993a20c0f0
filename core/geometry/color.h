#pragma once

#include <cstdint>
#include <ostream>

namespace cblox {

/// 8-bit RGB colour (sRGB, as delivered by the camera). Plain value type; thread-safe to read
/// concurrently.
struct Color {
  uint8_t r = 0, g = 0, b = 0;

  friend bool operator==(const Color&, const Color&) = default;
};

/// Prints "(r, g, b)"; for test output and logs. Thread-safe (no shared state).
inline std::ostream& operator<<(std::ostream& os, const Color& c) {
  return os << '(' << static_cast<int>(c.r) << ", " << static_cast<int>(c.g) << ", "
            << static_cast<int>(c.b) << ')';
}

}  // namespace cblox
