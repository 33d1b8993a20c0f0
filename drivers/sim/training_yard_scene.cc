#include "drivers/sim/training_yard_scene.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "core/mesh/primitive_meshes.h"

namespace cblox {
namespace {

using Eigen::Vector3d;
using Eigen::Vector3f;

constexpr float kPi = 3.14159265358979323846f;
constexpr float kSize = 30.0f;  ///< the yard is [0, kSize]^2
constexpr float kWallHeight = 4.0f;
constexpr float kPathClearance = 1.5f;  ///< horizontal gap between an object and every path

/// Horizontal positions (and heights) of the camera along all of the scene's paths.
std::vector<Vector3d> pathSamples(const BuiltinScene& scene) {
  std::vector<Vector3d> samples;
  for (TrajectoryKind kind : {TrajectoryKind::kLoop, TrajectoryKind::kOrbit,
                              TrajectoryKind::kLawnMower, TrajectoryKind::kFigureEight}) {
    for (const StampedPose& pose : makeSceneTrajectory(scene, kind, 5.0)) {
      samples.push_back(pose.T_G_C.translation());
    }
  }
  return samples;
}

/// True when an object of footprint radius `radius` and height `top` at (x, y) keeps
/// kPathClearance from every path sample below top + kPathClearance.
bool clearOfPaths(const std::vector<Vector3d>& samples, float x, float y, float radius, float top) {
  for (const Vector3d& p : samples) {
    if (p.z() > top + kPathClearance) continue;
    if (std::hypot(p.x() - x, p.y() - y) < radius + kPathClearance) return false;
  }
  return true;
}

Color randomColor(std::mt19937& rng) {
  std::uniform_int_distribution<int> channel(40, 235);
  return Color{static_cast<uint8_t>(channel(rng)), static_cast<uint8_t>(channel(rng)),
               static_cast<uint8_t>(channel(rng))};
}

/// A random object's kind and sizes, drawn before it is placed (so the placement can be
/// tested against the paths first).
struct ObjectShape {
  int kind = 0;
  float a = 0, b = 0, c = 0;  ///< kind-specific sizes
  float yaw = 0;
  float radius = 0;  ///< horizontal footprint radius
  float top = 0;     ///< height above the ground
};

ObjectShape randomShape(std::mt19937& rng) {
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  ObjectShape s;
  s.kind = static_cast<int>(unit(rng) * 7.0f) % 7;
  s.yaw = unit(rng) * kPi;
  switch (s.kind) {
    case 0:  // turned box
    case 1:  // stack of two boxes
      s.a = 0.4f + 2.0f * unit(rng);
      s.b = 0.4f + 1.6f * unit(rng);
      s.c = 0.3f + 2.2f * unit(rng);
      s.radius = 0.5f * std::hypot(s.a, s.b);
      s.top = s.kind == 0 ? s.c : 1.6f * s.c;
      break;
    case 2:  // standing cylinder
      s.a = 0.15f + 0.8f * unit(rng);
      s.c = 0.5f + 2.5f * unit(rng);
      s.radius = s.a;
      s.top = s.c;
      break;
    case 3:  // lying cylinder (a pipe or log)
      s.a = 0.15f + 0.4f * unit(rng);
      s.b = 1.0f + 3.0f * unit(rng);
      s.radius = 0.5f * s.b + s.a;
      s.top = 2.0f * s.a;
      break;
    case 4:  // cone
      s.a = 0.3f + 0.9f * unit(rng);
      s.c = 0.6f + 2.4f * unit(rng);
      s.radius = s.a;
      s.top = s.c;
      break;
    case 5:  // sphere on a plinth
      s.a = 0.3f + 0.9f * unit(rng);
      s.c = 0.2f + 0.8f * unit(rng);
      s.radius = std::max(s.a, 0.6f * s.a + 0.2f);
      s.top = s.c + 2.0f * s.a;
      break;
    default:  // pipe arch: half torus standing on the ground
      s.a = 0.6f + 1.2f * unit(rng);
      s.b = 0.08f + 0.2f * unit(rng);
      s.radius = s.a + s.b;
      s.top = s.a + s.b;
      break;
  }
  return s;
}

void appendShape(Mesh* m, const ObjectShape& s, float x, float y, std::mt19937& rng) {
  const Color color = randomColor(rng);
  const Eigen::Matrix3f yaw = Eigen::AngleAxisf(s.yaw, Vector3f::UnitZ()).toRotationMatrix();
  const Vector3f along = yaw * Vector3f::UnitX();
  switch (s.kind) {
    case 0:
      appendOrientedBox(m, Transformation(yaw, Vector3f(x, y, 0.5f * s.c)),
                        Vector3f(0.5f * s.a, 0.5f * s.b, 0.5f * s.c), color);
      break;
    case 1:
      appendOrientedBox(m, Transformation(yaw, Vector3f(x, y, 0.5f * s.c)),
                        Vector3f(0.5f * s.a, 0.5f * s.b, 0.5f * s.c), color);
      appendOrientedBox(
          m,
          Transformation(Eigen::AngleAxisf(s.yaw + 0.5f, Vector3f::UnitZ()).toRotationMatrix(),
                         Vector3f(x, y, 1.3f * s.c)),
          Vector3f(0.3f * s.a, 0.3f * s.b, 0.3f * s.c), randomColor(rng));
      break;
    case 2:
      appendCylinder(m, Vector3f(x, y, 0.0f), Vector3f(0, 0, s.c), s.a, 24, color);
      break;
    case 3:
      appendCylinder(m, Vector3f(x, y, s.a) - 0.5f * s.b * along, s.b * along, s.a, 20, color);
      break;
    case 4:
      appendCone(m, Vector3f(x, y, 0.0f), Vector3f(0, 0, s.c), s.a, 24, color);
      break;
    case 5:
      appendCylinder(m, Vector3f(x, y, 0.0f), Vector3f(0, 0, s.c), 0.6f * s.a + 0.2f, 16,
                     randomColor(rng));
      appendSphere(m, Vector3f(x, y, s.c + s.a), s.a, 10, 16, color);
      break;
    default:
      // Ends of the tube sink 2 cm into the ground so the arch stands on it.
      appendPipeBend(m, Vector3f(x, y, -0.02f), along, Vector3f::UnitZ(), s.a, s.b, kPi, 16, 12,
                     color);
      break;
  }
}

/// Doors, windows and plaques protruding 4-10 cm from the inner faces of the walls.
void appendWallDetails(Mesh* m, std::mt19937& rng) {
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  for (int side = 0; side < 4; ++side) {
    for (float u = 1.0f + 2.0f * unit(rng); u < kSize - 2.5f; u += 1.5f + 3.0f * unit(rng)) {
      const float width = 0.6f + 1.6f * unit(rng);
      const float z0 = unit(rng) < 0.3f ? 0.0f : 0.3f + 1.5f * unit(rng);
      const float height = std::min(kWallHeight - 0.2f - z0, 0.5f + 2.0f * unit(rng));
      const float depth = 0.04f + 0.06f * unit(rng);
      const float u1 = std::min(u + width, kSize - 0.5f);
      Eigen::AlignedBox3f b;
      switch (side) {
        case 0:  // wall y = 0
          b = Eigen::AlignedBox3f(Vector3f(u, 0.0f, z0), Vector3f(u1, depth, z0 + height));
          break;
        case 1:  // wall y = kSize
          b = Eigen::AlignedBox3f(Vector3f(u, kSize - depth, z0), Vector3f(u1, kSize, z0 + height));
          break;
        case 2:  // wall x = 0
          b = Eigen::AlignedBox3f(Vector3f(0.0f, u, z0), Vector3f(depth, u1, z0 + height));
          break;
        default:  // wall x = kSize
          b = Eigen::AlignedBox3f(Vector3f(kSize - depth, u, z0), Vector3f(kSize, u1, z0 + height));
          break;
      }
      appendBox(m, b, randomColor(rng));
      u = u1;
    }
  }
}

}  // namespace

BuiltinScene makeTrainingYard() {
  BuiltinScene scene;
  scene.name = "yard";
  scene.description =
      "training yard 30 x 30 m: walled courtyard with scattered boxes, cylinders, cones, "
      "spheres and pipe arches (vocabulary training, not an evaluation scene)";
  scene.loop_waypoints = {Vector3d(6, 6, 1.5), Vector3d(24, 6, 1.7), Vector3d(24, 24, 1.5),
                          Vector3d(6, 24, 1.7)};
  scene.orbit_centre = Vector3d(15, 15, 2.5);
  scene.orbit_radius = 9.0;
  scene.orbit_look_at = Vector3d(15, 15, 0.5);
  scene.survey_min = Eigen::Vector2d(5, 5);
  scene.survey_max = Eigen::Vector2d(25, 25);
  scene.survey_height = 7.5;
  scene.survey_spacing = 5.0;
  scene.eight_centre = Vector3d(15, 15, 2.0);
  scene.eight_half_x = 10.0;
  scene.eight_half_y = 6.0;
  scene.motion.speed_mps = 1.5;
  scene.motion.turn_radius_m = 2.0;
  scene.motion.pitch_down_rad = 0.2;
  scene.depth_max_m = 20.0;
  scene.texture_wavelength_m = 0.5;

  Mesh& m = scene.mesh;
  appendQuad(&m, Vector3f(0, 0, 0), Vector3f(kSize, 0, 0), Vector3f(0, kSize, 0),
             Color{150, 140, 115}, 15, 15);
  const float t = 0.4f;  // wall thickness, outside the yard
  appendBox(&m, Eigen::AlignedBox3f(Vector3f(-t, -t, 0), Vector3f(kSize + t, 0, kWallHeight)),
            Color{185, 160, 130});
  appendBox(
      &m, Eigen::AlignedBox3f(Vector3f(-t, kSize, 0), Vector3f(kSize + t, kSize + t, kWallHeight)),
      Color{150, 165, 180});
  appendBox(&m, Eigen::AlignedBox3f(Vector3f(-t, 0, 0), Vector3f(0, kSize, kWallHeight)),
            Color{175, 185, 150});
  appendBox(&m, Eigen::AlignedBox3f(Vector3f(kSize, 0, 0), Vector3f(kSize + t, kSize, kWallHeight)),
            Color{195, 170, 170});
  std::mt19937 rng(23);
  appendWallDetails(&m, rng);

  const std::vector<Vector3d> samples = pathSamples(scene);
  std::uniform_real_distribution<float> position(1.5f, kSize - 1.5f);
  std::vector<Vector3f> placed;  // x, y, footprint radius
  for (int attempt = 0; attempt < 4000 && placed.size() < 70; ++attempt) {
    const ObjectShape shape = randomShape(rng);
    const float x = position(rng), y = position(rng);
    const bool inside = x - shape.radius > 0.3f && x + shape.radius < kSize - 0.3f &&
                        y - shape.radius > 0.3f && y + shape.radius < kSize - 0.3f;
    const bool apart = std::none_of(placed.begin(), placed.end(), [&](const Vector3f& o) {
      return std::hypot(o.x() - x, o.y() - y) < o.z() + shape.radius + 0.3f;
    });
    if (!inside || !apart || !clearOfPaths(samples, x, y, shape.radius, shape.top)) continue;
    appendShape(&m, shape, x, y, rng);
    placed.emplace_back(x, y, shape.radius);
  }
  return scene;
}

}  // namespace cblox
