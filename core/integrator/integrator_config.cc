#include "core/integrator/integrator_config.h"

#include <cmath>
#include <sstream>

namespace cblox {

std::string IntegratorConfig::validate(float voxel_size) const {
  std::ostringstream error;
  auto finite_positive = [](double value) { return std::isfinite(value) && value > 0.0; };
  if (!finite_positive(voxel_size)) {
    error << "voxel_size must be finite and > 0, got " << voxel_size;
  } else if (!finite_positive(truncation_distance_m) || truncation_distance_m < voxel_size) {
    error << "truncation_distance_m must be finite and >= voxel_size (" << voxel_size << "), got "
          << truncation_distance_m;
  } else if (!finite_positive(max_weight)) {
    error << "max_weight must be finite and > 0, got " << max_weight;
  } else if (!std::isfinite(min_ray_length_m) || min_ray_length_m < 0.0f) {
    error << "min_ray_length_m must be finite and >= 0, got " << min_ray_length_m;
  } else if (!std::isfinite(max_ray_length_m) || max_ray_length_m <= min_ray_length_m) {
    error << "max_ray_length_m must be finite and > min_ray_length_m (" << min_ray_length_m
          << "), got " << max_ray_length_m;
  } else if (!std::isfinite(projective_carving_depth_m) || projective_carving_depth_m < 0.0f) {
    error << "projective_carving_depth_m must be finite and >= 0 (0 = no carving), got "
          << projective_carving_depth_m;
  } else if (num_threads < 1 || num_threads > 64) {
    error << "num_threads must be in [1, 64], got " << num_threads;
  } else if (!finite_positive(start_voxel_subsampling_factor) ||
             start_voxel_subsampling_factor > 64.0f) {
    error << "start_voxel_subsampling_factor must be in (0, 64], got "
          << start_voxel_subsampling_factor;
  } else if (max_consecutive_ray_collisions < 0) {
    error << "max_consecutive_ray_collisions must be >= 0, got " << max_consecutive_ray_collisions;
  } else if (!std::isfinite(max_integration_time_s) || max_integration_time_s < 0.0) {
    error << "max_integration_time_s must be finite and >= 0 (0 = unlimited), got "
          << max_integration_time_s;
  } else if (approx_set_log2_buckets < 16 || approx_set_log2_buckets > 28) {
    error << "approx_set_log2_buckets must be in [16, 28], got " << approx_set_log2_buckets;
  }
  return error.str();
}

}  // namespace cblox
