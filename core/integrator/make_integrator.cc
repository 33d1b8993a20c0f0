#include "core/integrator/make_integrator.h"

#include <algorithm>

#include "core/geometry/depth_to_point_cloud.h"
#include "core/integrator/projective_tsdf_integrator.h"
#include "core/integrator/ray_casting_integrator.h"

namespace cblox {

const char* integratorTypeName(IntegratorType type) {
  switch (type) {
    case IntegratorType::kFast:
      return "fast";
    case IntegratorType::kSimple:
      return "simple";
    case IntegratorType::kProjective:
      return "projective";
  }
  return "?";
}

std::optional<IntegratorType> integratorTypeFromName(std::string_view name) {
  for (const IntegratorType type :
       {IntegratorType::kFast, IntegratorType::kSimple, IntegratorType::kProjective}) {
    if (name == integratorTypeName(type)) return type;
  }
  return std::nullopt;
}

namespace {

class ProjectiveDepthIntegrator final : public DepthIntegrator {
 public:
  ProjectiveDepthIntegrator(const IntegratorConfig& config, TsdfLayer* layer)
      : integrator_(config, layer) {}
  IntegrationStats integrateDepthImage(const Transformation& T_L_C, const DepthImage& depth,
                                       const PinholeCamera& camera,
                                       const ColorImage* color) override {
    return integrator_.integrateDepthImage(T_L_C, depth, camera, color);
  }
  IntegratorType type() const override { return IntegratorType::kProjective; }

 private:
  ProjectiveTsdfIntegrator integrator_;
};

class RayCastingDepthIntegrator final : public DepthIntegrator {
 public:
  RayCastingDepthIntegrator(IntegratorType type, const IntegratorConfig& config,
                            TsdfLayer* layer)
      : type_(type),
        integrator_(type == IntegratorType::kFast ? RayCastingIntegrator::Mode::kFast
                                                  : RayCastingIntegrator::Mode::kSimple,
                    config, layer) {
    conversion_.min_depth_m = std::max(1e-3f, config.min_ray_length_m);
    conversion_.max_depth_m = std::max(conversion_.min_depth_m * 2.0f, config.max_ray_length_m);
  }
  IntegrationStats integrateDepthImage(const Transformation& T_L_C, const DepthImage& depth,
                                       const PinholeCamera& camera,
                                       const ColorImage* color) override {
    const PointCloud cloud = depthToPointCloud(depth, camera, color, conversion_);
    return integrator_.integratePointCloud(T_L_C, cloud);
  }
  IntegratorType type() const override { return type_; }

 private:
  IntegratorType type_;
  RayCastingIntegrator integrator_;
  DepthConversionConfig conversion_;
};

}  // namespace

std::unique_ptr<DepthIntegrator> makeIntegrator(IntegratorType type,
                                                const IntegratorConfig& config,
                                                TsdfLayer* layer) {
  if (type == IntegratorType::kProjective) {
    return std::make_unique<ProjectiveDepthIntegrator>(config, layer);
  }
  return std::make_unique<RayCastingDepthIntegrator>(type, config, layer);
}

}  // namespace cblox
