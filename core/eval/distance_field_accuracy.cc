#include "core/eval/distance_field_accuracy.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>

#include "core/common/quantile.h"
#include "core/common/thread_team.h"

namespace cblox {
namespace {

double uniform01(std::mt19937_64& rng) { return static_cast<double>(rng() >> 11) * 0x1.0p-53; }

/// The ray of `view` through p_G, scaled to unit depth (its parameter is the depth), with
/// t_far unset, when p lies in the view's image and depth range; *p_D is p in the view.
bool viewRayThrough(const DepthView& view, const Eigen::Vector3d& p_G, Eigen::Vector3d* p_D,
                    Ray* ray) {
  *p_D = view.T_G_D.inverse() * p_G;
  const double z = p_D->z();
  if (!(z >= view.min_depth_m) || !(z <= view.max_depth_m)) return false;
  const PinholeIntrinsics& k = view.intrinsics;
  const double u = k.fx * p_D->x() / z + k.cx;
  const double w = k.fy * p_D->y() / z + k.cy;
  if (!(u >= 0.0 && u < k.width && w >= 0.0 && w < k.height)) return false;
  ray->origin = view.T_G_D.translation().cast<float>();
  ray->direction = (view.T_G_D.rotation() * (*p_D / z)).cast<float>();
  ray->t_near = 0.0f;
  return true;
}

/// True if some view measured a surface at least `free_depth` behind p on the ray through it.
bool observedFree(const TriangleMeshRaycaster& truth, std::span<const DepthView> views, int stride,
                  double free_depth, const Eigen::Vector3d& p_G) {
  for (size_t v = 0; v < views.size(); v += static_cast<size_t>(stride)) {
    const DepthView& view = views[v];
    Eigen::Vector3d p_D;
    Ray ray;
    if (!viewRayThrough(view, p_G, &p_D, &ray)) continue;
    const double z = p_D.z();
    ray.t_far = static_cast<float>(view.max_depth_m);
    RaycastHit hit;
    if (!truth.intersect(ray, &hit)) continue;  // no depth measured there
    if (static_cast<double>(hit.t) * (p_D / z).norm() > view.max_ray_length_m) continue;
    if (static_cast<double>(hit.t) - z >= free_depth) return true;
  }
  return false;
}

/// True if some view saw the surface point q: in its image, depth range and ray length, the
/// first hit on the ray through q within a centimetre of q's depth.
bool seen(const TriangleMeshRaycaster& truth, std::span<const DepthView> views, int stride,
          const Eigen::Vector3d& q_G) {
  constexpr double kTolerance = 0.01;
  for (size_t v = 0; v < views.size(); v += static_cast<size_t>(stride)) {
    const DepthView& view = views[v];
    Eigen::Vector3d q_D;
    Ray ray;
    if (!viewRayThrough(view, q_G, &q_D, &ray) || q_D.norm() > view.max_ray_length_m) continue;
    const double z = q_D.z();
    ray.t_far = static_cast<float>(z + kTolerance);
    RaycastHit hit;
    if (truth.intersect(ray, &hit) && static_cast<double>(hit.t) >= z - kTolerance) return true;
  }
  return false;
}

/// Median, p99 and max of *errors (reordered) into the three outputs.
void summarize(std::vector<double>* errors, double* median, double* p99, double* max) {
  if (errors->empty()) return;
  *max = *std::max_element(errors->begin(), errors->end());
  *p99 = quantile(errors, 0.99);
  *median = quantile(errors, 0.5);
}

}  // namespace

std::string DistanceTruthConfig::validate() const {
  if (samples < 1) return "samples must be >= 1";
  if (!std::isfinite(truncation_m) || truncation_m < 0.0)
    return "truncation_m must be finite, >= 0";
  if (!std::isfinite(free_margin_m) || free_margin_m < 0.0) {
    return "free_margin_m must be finite, >= 0";
  }
  if (view_stride < 1) return "view_stride must be >= 1";
  if (num_threads < 1 || num_threads > 64) return "num_threads must be in [1, 64]";
  return {};
}

double signedDistanceToMesh(const TriangleMeshRaycaster& truth, const Eigen::Vector3d& p,
                            Eigen::Vector3d* closest) {
  const ClosestSurfacePoint nearest = truth.closestPoint(p);
  if (closest != nullptr) *closest = nearest.point;
  const double distance = nearest.distance;
  static const Eigen::Vector3f kDirections[3] = {
      Eigen::Vector3f(0.267f, 0.534f, 0.802f).normalized(),
      Eigen::Vector3f(-0.577f, 0.211f, -0.789f).normalized(),
      Eigen::Vector3f(0.713f, -0.682f, 0.163f).normalized()};
  int inside = 0, outside = 0;
  for (const Eigen::Vector3f& d : kDirections) {
    Ray ray;
    ray.origin = p.cast<float>();
    ray.direction = d;
    RaycastHit hit;
    if (!truth.intersect(ray, &hit)) continue;
    ++(hit.normal.dot(d) > 0.0f ? inside : outside);
  }
  return inside > outside ? -distance : distance;
}

std::optional<std::vector<DistanceTruthSample>> sampleDistanceTruth(
    const TriangleMeshRaycaster& truth, std::span<const DepthView> views,
    const DistanceTruthConfig& config, std::string* error) {
  auto fail = [&](const std::string& message) {
    if (error != nullptr) *error = message;
    return std::nullopt;
  };
  if (const std::string problem = config.validate(); !problem.empty()) return fail(problem);
  if (config.box.isEmpty() || !config.box.min().allFinite() || !config.box.max().allFinite()) {
    return fail("the sample box is empty or not finite");
  }
  std::vector<DistanceTruthSample> samples(config.samples);
  std::mt19937_64 rng(config.seed);
  const Eigen::Vector3d size = config.box.sizes();
  for (DistanceTruthSample& s : samples) {
    const double x = uniform01(rng), y = uniform01(rng), z = uniform01(rng);
    s.p_G = config.box.min() + Eigen::Vector3d(x, y, z).cwiseProduct(size);
  }
  const double free_depth = config.truncation_m + config.free_margin_m;
  const int threads = config.num_threads;
  runThreadTeam(threads, [&](int id) {
    for (size_t i = static_cast<size_t>(id); i < samples.size();
         i += static_cast<size_t>(threads)) {
      DistanceTruthSample& s = samples[i];
      Eigen::Vector3d closest;
      s.signed_distance_m = signedDistanceToMesh(truth, s.p_G, &closest);
      s.observed_free = s.signed_distance_m > 0.0 &&
                        observedFree(truth, views, config.view_stride, free_depth, s.p_G);
      s.nearest_surface_seen = seen(truth, views, config.view_stride, closest);
    }
  });
  return samples;
}

DistanceFieldAccuracy scoreDistanceField(std::span<const DistanceTruthSample> truth,
                                         std::span<const FieldAnswer> answers, double voxel_m,
                                         double max_distance_m) {
  if (truth.size() != answers.size()) {
    throw std::invalid_argument("scoreDistanceField: truth and answers differ in length");
  }
  DistanceFieldAccuracy a;
  a.samples = truth.size();
  std::vector<double> errors, seen_errors;
  for (size_t i = 0; i < truth.size(); ++i) {
    const DistanceTruthSample& t = truth[i];
    const FieldAnswer& f = answers[i];
    const bool known = f.state != VoxelState::kUnknown;
    if (f.state == VoxelState::kFree) ++a.answered_free;
    if (f.state == VoxelState::kOccupied) ++a.answered_occupied;
    if (!known) ++a.answered_unknown;
    if (t.observed_free) {
      ++a.observed_free;
      if (!known) ++a.observed_free_unknown;
    }
    const bool near = t.signed_distance_m < voxel_m;
    if (near) {
      ++a.near_obstacle;
      if (f.state == VoxelState::kFree && f.distance_m > 1.01 * voxel_m) {
        const bool by_a_voxel = f.distance_m - t.signed_distance_m > voxel_m;
        ++a.unsafe;
        if (by_a_voxel) ++a.unsafe_by_a_voxel;
        if (t.nearest_surface_seen) {
          ++a.unsafe_seen;
          if (by_a_voxel) ++a.unsafe_seen_by_a_voxel;
        }
      }
    }
    if (t.signed_distance_m > max_distance_m && f.state == VoxelState::kOccupied) {
      ++a.far_answered_occupied;
    }
    if (known && std::abs(t.signed_distance_m) < max_distance_m - voxel_m) {
      errors.push_back(std::abs(f.distance_m - t.signed_distance_m) / voxel_m);
      if (t.nearest_surface_seen) seen_errors.push_back(errors.back());
    }
  }
  a.compared = errors.size();
  a.compared_seen = seen_errors.size();
  summarize(&errors, &a.error_median_voxels, &a.error_p99_voxels, &a.error_max_voxels);
  summarize(&seen_errors, &a.seen_error_median_voxels, &a.seen_error_p99_voxels,
            &a.seen_error_max_voxels);
  return a;
}

}  // namespace cblox
