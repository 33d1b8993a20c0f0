#include "core/integrator/integrator_config.h"

#include <cmath>
#include <limits>
#include <stdexcept>

#include <gtest/gtest.h>

#include "core/integrator/projective_tsdf_integrator.h"
#include "core/integrator/ray_casting_integrator.h"
#include "core/tsdf/tsdf_layer.h"

namespace cblox {
namespace {

TEST(IntegratorConfig, DefaultsAreValid) { EXPECT_EQ(IntegratorConfig{}.validate(0.02f), ""); }

TEST(IntegratorConfig, MessagesNameTheField) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  struct Case {
    void (*mutate)(IntegratorConfig&);
    const char* field;
  };
  const Case cases[] = {
      {[](IntegratorConfig& c) { c.truncation_distance_m = 0.01f; }, "truncation_distance_m"},
      {[](IntegratorConfig& c) {
         c.truncation_distance_m = std::numeric_limits<float>::quiet_NaN();
       },
       "truncation_distance_m"},
      {[](IntegratorConfig& c) { c.max_weight = 0.0f; }, "max_weight"},
      {[](IntegratorConfig& c) { c.min_ray_length_m = -1.0f; }, "min_ray_length_m"},
      {[](IntegratorConfig& c) { c.max_ray_length_m = 0.05f; }, "max_ray_length_m"},
      {[](IntegratorConfig& c) { c.projective_carving_depth_m = -1.0f; },
       "projective_carving_depth_m"},
      {[](IntegratorConfig& c) {
         c.projective_carving_depth_m = std::numeric_limits<float>::infinity();
       },
       "projective_carving_depth_m"},
      {[](IntegratorConfig& c) { c.num_threads = 0; }, "num_threads"},
      {[](IntegratorConfig& c) { c.start_voxel_subsampling_factor = 0.0f; },
       "start_voxel_subsampling_factor"},
      {[](IntegratorConfig& c) { c.max_consecutive_ray_collisions = -1; },
       "max_consecutive_ray_collisions"},
      {[](IntegratorConfig& c) { c.max_integration_time_s = -0.5; }, "max_integration_time_s"},
      {[](IntegratorConfig& c) { c.approx_set_log2_buckets = 8; }, "approx_set_log2_buckets"},
  };
  for (const Case& test_case : cases) {
    IntegratorConfig config;
    test_case.mutate(config);
    const std::string error = config.validate(0.02f);
    EXPECT_NE(error.find(test_case.field), std::string::npos)
        << "expected '" << test_case.field << "' in '" << error << "'";
  }
  EXPECT_NE(IntegratorConfig{}.validate(nan).find("voxel_size"), std::string::npos);
}

TEST(IntegratorConfig, IntegratorsRejectInvalidConfigWithTheMessage) {
  TsdfLayer layer(LayerConfig{0.02f, 8});
  IntegratorConfig config;
  config.num_threads = 0;
  try {
    FastTsdfIntegrator integrator(config, &layer);
    FAIL() << "expected std::invalid_argument";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("num_threads"), std::string::npos) << e.what();
  }
  EXPECT_THROW(ProjectiveTsdfIntegrator(config, &layer), std::invalid_argument);
  EXPECT_THROW(SimpleTsdfIntegrator(IntegratorConfig{}, nullptr), std::invalid_argument);
}

TEST(LayerConfig, InvalidGeometryIsRejectedNamingTheField) {
  EXPECT_NE(LayerConfig({0.0f, 8}).validate().find("voxel_size"), std::string::npos);
  EXPECT_NE(LayerConfig({-0.1f, 8}).validate().find("voxel_size"), std::string::npos);
  EXPECT_NE(LayerConfig({0.02f, 12}).validate().find("voxels_per_side"), std::string::npos);
  EXPECT_NE(LayerConfig({0.02f, 1}).validate().find("voxels_per_side"), std::string::npos);
  EXPECT_NE(LayerConfig({0.02f, 128}).validate().find("voxels_per_side"), std::string::npos);
  EXPECT_THROW(TsdfLayer(LayerConfig{0.02f, 6}), std::invalid_argument);
  EXPECT_EQ(LayerConfig({0.05f, 16}).validate(), "");
}

}  // namespace
}  // namespace cblox
