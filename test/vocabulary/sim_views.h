#pragma once

#include <memory>
#include <string>
#include <vector>

#include "core/features/orb_descriptor.h"
#include "core/geometry/se3.h"
#include "drivers/sim/builtin_scenes.h"
#include "drivers/sim/sim_renderer.h"

namespace cblox::test {

/// One rendered left-camera view, its ORB descriptors (OrbExtractor defaults) and its depth
/// at every 4th pixel (for the ground-truth view overlap).
struct SimView {
  Transformationd T_G_C;
  std::vector<OrbDescriptor> descriptors;
  DepthImage coarse_depth;          ///< depth of pixel (4u + 2, 4v + 2); 0 = nothing seen
  PinholeIntrinsics coarse_camera;  ///< intrinsics of coarse_depth
};

/// Renders left-camera grey images of a built-in scene (752 x 480 EuRoC-like rig, the
/// scene's texture wavelength) and extracts ORB descriptors. Not thread-safe.
class SimViewRenderer {
 public:
  /// texture_seed: 1 is what evaluation runs render; training uses another (2).
  SimViewRenderer(const std::string& scene_name, uint32_t texture_seed);

  SimView render(const Transformationd& T_G_C) const;
  const BuiltinScene& scene() const { return scene_; }

 private:
  BuiltinScene scene_;
  std::unique_ptr<SimRenderer> renderer_;
};

/// Ground-truth overlap: the fraction of the surface points `a` sees (coarse depth) that `b`
/// sees too (in front of b, inside its image, and not hidden: b's depth at the projection
/// within 5 % + 2 cm). 0 when a sees nothing.
double viewOverlap(const SimView& a, const SimView& b);

}  // namespace cblox::test
