#include "drivers/synthetic/demo_room_orbit.h"

#include "drivers/synthetic/scenes.h"

namespace cblox {

SyntheticDepthSource DemoRoomOrbit::source() const {
  return SyntheticDepthSource(
      makeDemoRoom(), intrinsics(),
      makeOrbitTrajectory(Eigen::Vector3d(0, 0, 0), orbit_radius_m, orbit_height_m, frames,
                          Eigen::Vector3d(0, 0, look_at_height_m)),
      rate_hz, max_range_m);
}

}  // namespace cblox
