#include "drivers/synthetic/scenes.h"

#include <cmath>
#include <numbers>
#include <stdexcept>

namespace cblox {
namespace {

using Eigen::Vector3d;

CheckerTexture checker(Color a, Color b, double cell_size) { return {a, b, cell_size}; }

}  // namespace

AnalyticScene makeSphereScene() {
  AnalyticScene scene;
  scene.add(Sphere{Vector3d::Zero(), 0.5, checker({200, 40, 40}, {240, 220, 200}, 0.1)});
  scene.add(
      Plane{Vector3d(0, 0, -0.5), Vector3d::UnitZ(), checker({90, 90, 90}, {180, 180, 180}, 0.25)});
  return scene;
}

AnalyticScene makePlaneScene(const Vector3d& point, const Vector3d& normal, double cell_size) {
  AnalyticScene scene;
  scene.add(Plane{point, normal, checker({40, 40, 160}, {220, 220, 220}, cell_size)});
  return scene;
}

AnalyticScene makeDemoRoom() {
  AnalyticScene scene;
  scene.add(
      Room{Vector3d(-3, -2, 0), Vector3d(3, 2, 3), checker({200, 190, 170}, {120, 110, 100}, 0.5)});
  // Table centred at (1, 0.5): top 1.2 x 0.8 x 0.05 m, legs 5 cm square, 0.72 m high.
  const CheckerTexture wood = checker({150, 100, 50}, {110, 70, 30}, 0.1);
  const double top_z0 = 0.72, top_z1 = 0.77, leg = 0.05;
  const double x0 = 0.4, x1 = 1.6, y0 = 0.1, y1 = 0.9;
  scene.add(SolidBox{Vector3d(x0, y0, top_z0), Vector3d(x1, y1, top_z1), wood});
  for (const double lx : {x0, x1 - leg}) {
    for (const double ly : {y0, y1 - leg}) {
      scene.add(SolidBox{Vector3d(lx, ly, 0.0), Vector3d(lx + leg, ly + leg, top_z0), wood});
    }
  }
  scene.add(Sphere{Vector3d(-1.0, -0.8, 0.3), 0.3, checker({30, 120, 200}, {250, 250, 250}, 0.1)});
  scene.add(Cylinder{-1.8, 1.2, 0.2, 0.0, 3.0, checker({60, 160, 60}, {230, 230, 120}, 0.15)});
  return scene;
}

Transformationd lookAt(const Vector3d& position_G, const Vector3d& look_at_G) {
  const Vector3d forward = look_at_G - position_G;
  if (!(forward.norm() > 1e-12)) {
    throw std::invalid_argument("lookAt: camera position coincides with the look-at point");
  }
  const Vector3d z_C = forward.normalized();
  const Vector3d x_unnormalised = z_C.cross(Vector3d::UnitZ());  // horizontal, "right"
  if (!(x_unnormalised.norm() > 1e-9)) {
    throw std::invalid_argument("lookAt: viewing direction is vertical, camera x is undefined");
  }
  const Vector3d x_C = x_unnormalised.normalized();
  const Vector3d y_C = z_C.cross(x_C);  // points down
  Eigen::Matrix3d R_G_C;
  R_G_C.col(0) = x_C;
  R_G_C.col(1) = y_C;
  R_G_C.col(2) = z_C;
  return Transformationd(R_G_C, position_G);
}

std::vector<Transformationd> makeOrbitTrajectory(const Vector3d& centre, double radius,
                                                 double height, int num_frames,
                                                 const Vector3d& look_at) {
  std::vector<Transformationd> poses;
  if (num_frames <= 0) return poses;
  poses.reserve(static_cast<size_t>(num_frames));
  for (int k = 0; k < num_frames; ++k) {
    const double angle = 2.0 * std::numbers::pi * k / num_frames;
    const Vector3d position =
        centre + Vector3d(radius * std::cos(angle), radius * std::sin(angle), height);
    poses.push_back(lookAt(position, look_at));
  }
  return poses;
}

}  // namespace cblox
