#pragma once

// One place that turns an integrator choice into an integrator: the mapper and
// cblox-integrate both go through makeIntegrator().

#include <memory>
#include <optional>
#include <string_view>

#include "core/geometry/image.h"
#include "core/geometry/pinhole_camera.h"
#include "core/geometry/se3.h"
#include "core/integrator/integration_stats.h"
#include "core/integrator/integrator_config.h"
#include "core/tsdf/tsdf_layer.h"

namespace cblox {

/// Which TSDF integrator (README, "The integrators").
enum class IntegratorType { kFast, kSimple, kProjective };

/// "fast", "simple" or "projective". Thread-safe (pure).
const char* integratorTypeName(IntegratorType type);
/// The type named by integratorTypeName(), nullopt for any other name. Thread-safe (pure).
std::optional<IntegratorType> integratorTypeFromName(std::string_view name);

/// Any of the three integrators behind one call that takes a depth image. The ray-casting
/// ones turn the image into a point cloud first (depth range [max(1 mm, min_ray_length_m),
/// max(2 * min, max_ray_length_m)]); the projective one reads the image directly.
///
/// Thread safety: one call at a time per integrator, and nothing else may touch the layer
/// during the call (the integrators' own rule).
class DepthIntegrator {
 public:
  virtual ~DepthIntegrator() = default;
  /// `depth` holds z along the optical axis in metres (0, negative or non-finite = no
  /// measurement). `color`, when not null, is registered to the depth image. Throws
  /// std::invalid_argument on size mismatches.
  virtual IntegrationStats integrateDepthImage(const Transformation& T_L_C,
                                               const DepthImage& depth,
                                               const PinholeCamera& camera,
                                               const ColorImage* color) = 0;
  virtual IntegratorType type() const = 0;
};

/// An integrator of `type` writing into `layer` (not owned; must outlive it). Throws
/// std::invalid_argument naming an invalid field of `config`, or if layer is null.
std::unique_ptr<DepthIntegrator> makeIntegrator(IntegratorType type,
                                                const IntegratorConfig& config, TsdfLayer* layer);

}  // namespace cblox
