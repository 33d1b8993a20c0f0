#include "drivers/synthetic/analytic_scene.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <thread>

namespace cblox {

void AnalyticScene::add(Primitive primitive) {
  const std::string error = validate(primitive);
  if (!error.empty()) throw std::invalid_argument("AnalyticScene::add: " + error);
  if (auto* plane = std::get_if<Plane>(&primitive)) plane->normal.normalize();
  primitives_.push_back(std::move(primitive));
}

bool AnalyticScene::raycast(const Eigen::Vector3d& origin_G, const Eigen::Vector3d& dir_G,
                            double max_range, double* range, Color* color) const {
  const double norm = dir_G.norm();
  if (!(norm > 0.0) || !std::isfinite(norm) || !origin_G.allFinite() || !(max_range > 0.0)) {
    return false;
  }
  const Eigen::Vector3d dir = dir_G / norm;
  double best = max_range;
  const Primitive* best_primitive = nullptr;
  for (const Primitive& primitive : primitives_) {
    double t = 0.0;
    if (intersect(primitive, origin_G, dir, best, &t) && t <= best) {
      best = t;
      best_primitive = &primitive;
    }
  }
  if (best_primitive == nullptr) return false;
  *range = best;
  if (color != nullptr) *color = surfaceColor(*best_primitive, origin_G + best * dir);
  return true;
}

double AnalyticScene::signedDistance(const Eigen::Vector3d& p_G) const {
  double magnitude = std::numeric_limits<double>::infinity();
  bool inside_matter = false;
  for (const Primitive& primitive : primitives_) {
    const double d = cblox::signedDistance(primitive, p_G);
    magnitude = std::min(magnitude, std::abs(d));
    inside_matter = inside_matter || d < 0.0;
  }
  return inside_matter ? -magnitude : magnitude;
}

void AnalyticScene::renderDepth(const Transformationd& T_G_C, const PinholeCamera& camera,
                                DepthImage* depth, ColorImage* color, double max_range) const {
  if (depth == nullptr) throw std::invalid_argument("renderDepth: depth must be non-null");
  if (!(max_range > 0.0)) throw std::invalid_argument("renderDepth: max_range must be > 0");
  const int width = camera.width();
  const int height = camera.height();
  *depth = DepthImage(width, height, 0.0f);
  if (color != nullptr) *color = ColorImage(width, height, Color{});

  const Eigen::Matrix3d R_G_C = T_G_C.rotationMatrix();
  const Eigen::Vector3d origin_G = T_G_C.translation();
  constexpr int kNumThreads = 2;
  // Thread k renders rows k, k + 2, ...: interleaving balances rows that see near objects.
  // Each thread writes disjoint pixels, so no synchronisation is needed.
  auto render_rows = [&](int first_row) {
    for (int v = first_row; v < height; v += kNumThreads) {
      for (int u = 0; u < width; ++u) {
        const Eigen::Vector3d ray_C = camera.rayDirection(Eigen::Vector2d(u, v));  // z = 1
        const Eigen::Vector3d dir_C = ray_C.normalized();
        double range = 0.0;
        Color c;
        if (!raycast(origin_G, R_G_C * dir_C, max_range, &range, color != nullptr ? &c : nullptr)) {
          continue;
        }
        (*depth)(u, v) = static_cast<float>(range * dir_C.z());
        if (color != nullptr) (*color)(u, v) = c;
      }
    }
  };
  std::vector<std::thread> threads;
  threads.reserve(kNumThreads);
  for (int k = 0; k < kNumThreads; ++k) threads.emplace_back(render_rows, k);
  for (std::thread& thread : threads) thread.join();
}

}  // namespace cblox
