#pragma once

#include "drivers/synthetic/synthetic_frame_source.h"

namespace cblox {

/// The built-in synthetic room source: makeDemoRoom() rendered exactly along an orbit
/// (cblox-integrate --source synthetic-room, YAML section `synthetic`; the benches' analytic
/// room). Plain value type; the defaults are config/integrate.yaml's.
struct DemoRoomOrbit {
  int width = 640, height = 480;
  double fx = 525.0, fy = 525.0;  ///< the principal point is the image centre
  int frames = 60;
  double rate_hz = 30.0;
  double orbit_radius_m = 1.5;    ///< around the room's vertical axis
  double orbit_height_m = 1.4;    ///< camera height above the floor
  double look_at_height_m = 1.0;  ///< every camera looks at (0, 0, this)
  double max_range_m = 6.0;       ///< rendering range along a ray

  PinholeIntrinsics intrinsics() const {
    return {fx, fy, (width - 1) / 2.0, (height - 1) / 2.0, width, height};
  }
  /// The source of its frames; throws std::invalid_argument as SyntheticDepthSource does.
  SyntheticDepthSource source() const;
};

}  // namespace cblox
