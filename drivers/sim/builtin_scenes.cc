#include "drivers/sim/builtin_scenes.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <random>
#include <stdexcept>

#include "core/mesh/primitive_meshes.h"
#include "drivers/sim/training_yard_scene.h"

namespace cblox {
namespace {

using Eigen::AlignedBox3f;
using Eigen::Vector3d;
using Eigen::Vector3f;

constexpr float kPi = 3.14159265358979323846f;

AlignedBox3f box(float x0, float y0, float z0, float x1, float y1, float z1) {
  return AlignedBox3f(Vector3f(x0, y0, z0), Vector3f(x1, y1, z1));
}

/// A box given by its centre (x, y), footprint size (sx, sy), bottom z0 and height h.
AlignedBox3f boxAt(float x, float y, float sx, float sy, float z0, float h) {
  return box(x - sx / 2, y - sy / 2, z0, x + sx / 2, y + sy / 2, z0 + h);
}

Color shade(const Color& c, float factor) {
  auto f = [factor](uint8_t v) {
    return static_cast<uint8_t>(std::clamp(v * factor, 0.0f, 255.0f));
  };
  return Color{f(c.r), f(c.g), f(c.b)};
}

/// Floor, ceiling and four walls of the box [0, W] x [0, L] x [0, H] as separate quads facing
/// inwards (each its own surface and colour: floor, ceiling, wall y = 0, y = L, x = 0,
/// x = W), split into cells of about cell_size metres.
void appendInteriorShell(Mesh* mesh, float W, float L, float H, const std::array<Color, 6>& colors,
                         float cell_size) {
  auto cells = [cell_size](float length) {
    return std::max(1, static_cast<int>(std::lround(length / cell_size)));
  };
  const Vector3f x(W, 0, 0), y(0, L, 0), z(0, 0, H), o = Vector3f::Zero();
  appendQuad(mesh, o, x, y, colors[0], cells(W), cells(L));
  appendQuad(mesh, z, y, x, colors[1], cells(L), cells(W));
  appendQuad(mesh, o, z, x, colors[2], cells(H), cells(W));
  appendQuad(mesh, y, x, z, colors[3], cells(W), cells(H));
  appendQuad(mesh, o, y, z, colors[4], cells(L), cells(H));
  appendQuad(mesh, x, z, y, colors[5], cells(H), cells(L));
}

/// Four legs under a table top of footprint (sx, sy) centred at (x, y), leg height h.
void appendLegs(Mesh* mesh, float x, float y, float sx, float sy, float h, float leg,
                const Color& color) {
  for (int i = 0; i < 4; ++i) {
    const float lx = x + ((i & 1) ? 1 : -1) * (sx / 2 - leg);
    const float ly = y + ((i & 2) ? 1 : -1) * (sy / 2 - leg);
    appendBox(mesh, boxAt(lx, ly, leg, leg, 0.0f, h), color);
  }
}

/// A chair at (x, y) whose back is on the side `back_dir` (+1: +y, -1: -y).
void appendChair(Mesh* mesh, float x, float y, float back_dir, const Color& color) {
  appendLegs(mesh, x, y, 0.45f, 0.45f, 0.45f, 0.04f, shade(color, 0.7f));
  appendBox(mesh, boxAt(x, y, 0.45f, 0.45f, 0.45f, 0.05f), color);
  appendBox(mesh, boxAt(x, y + back_dir * 0.2f, 0.45f, 0.05f, 0.5f, 0.5f), color);
}

}  // namespace

std::vector<std::string> builtinSceneNames() { return {"room", "hall", "town", "yard"}; }

BuiltinScene makeBuiltinScene(const std::string& name) {
  if (name == "room") return makeLivingRoom();
  if (name == "hall") return makeIndustrialHall();
  if (name == "town") return makeTown();
  if (name == "yard") return makeTrainingYard();
  throw std::invalid_argument("unknown built-in scene '" + name +
                              "' (known: room, hall, town, yard)");
}

BuiltinScene makeLivingRoom() {
  BuiltinScene scene;
  scene.name = "room";
  scene.description = "living room 5 x 6.5 x 2.7 m with furniture";
  Mesh& m = scene.mesh;
  const float W = 5.0f, L = 6.5f, H = 2.7f;
  // Shell: floor, ceiling and walls as inward-facing quads (each a separate surface).
  appendInteriorShell(&m, W, L, H,
                      {Color{150, 110, 75}, Color{235, 235, 230}, Color{200, 190, 160},
                       Color{170, 195, 200}, Color{205, 180, 170}, Color{190, 200, 170}},
                      1.0f);

  // Sofa against the far wall (y = L).
  const Color sofa{120, 60, 55};
  appendBox(&m, box(1.2f, L - 1.0f, 0.0f, 3.6f, L - 0.1f, 0.45f), sofa);
  appendBox(&m, box(1.2f, L - 0.35f, 0.45f, 3.6f, L - 0.1f, 0.95f), shade(sofa, 0.9f));
  appendBox(&m, box(1.0f, L - 1.0f, 0.0f, 1.2f, L - 0.1f, 0.65f), shade(sofa, 0.8f));
  appendBox(&m, box(3.6f, L - 1.0f, 0.0f, 3.8f, L - 0.1f, 0.65f), shade(sofa, 0.8f));
  // Coffee table and rug in front of it.
  appendBox(&m, box(1.5f, 3.2f, 0.0f, 3.5f, 5.2f, 0.015f), Color{90, 80, 140});
  appendBox(&m, boxAt(2.5f, 4.4f, 1.1f, 0.6f, 0.38f, 0.05f), Color{110, 75, 45});
  appendLegs(&m, 2.5f, 4.4f, 1.1f, 0.6f, 0.38f, 0.05f, Color{80, 55, 35});
  // TV bench and TV on the near wall (y = 0).
  appendBox(&m, box(1.6f, 0.05f, 0.0f, 3.4f, 0.5f, 0.5f), Color{60, 60, 65});
  appendBox(&m, box(1.9f, 0.15f, 0.55f, 3.1f, 0.23f, 1.25f), Color{25, 25, 30});
  appendBox(&m, boxAt(2.5f, 0.19f, 0.3f, 0.2f, 0.5f, 0.05f), Color{40, 40, 45});
  // Book shelf on the wall x = 0 with rows of books.
  const Color wood{140, 100, 60};
  const float shelf_y0 = 1.0f, shelf_y1 = 2.6f;
  appendBox(&m, box(0.02f, shelf_y0, 0.0f, 0.37f, shelf_y0 + 0.04f, 2.0f), wood);
  appendBox(&m, box(0.02f, shelf_y1 - 0.04f, 0.0f, 0.37f, shelf_y1, 2.0f), wood);
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  for (int level = 0; level < 5; ++level) {
    const float z = 0.05f + 0.4f * level;
    appendBox(&m, box(0.02f, shelf_y0 + 0.04f, z - 0.03f, 0.37f, shelf_y1 - 0.04f, z), wood);
    float y = shelf_y0 + 0.06f;
    while (true) {
      const float thickness = 0.02f + 0.04f * unit(rng);
      if (y + thickness > shelf_y1 - 0.06f) break;
      const float height = 0.2f + 0.13f * unit(rng);
      const Color c{static_cast<uint8_t>(40 + 200 * unit(rng)),
                    static_cast<uint8_t>(40 + 200 * unit(rng)),
                    static_cast<uint8_t>(40 + 200 * unit(rng))};
      appendBox(&m, box(0.06f, y, z, 0.33f, y + thickness, z + height), c);
      y += thickness + 0.004f;
    }
  }
  // Dining table with four chairs near the wall x = W.
  appendBox(&m, boxAt(3.9f, 1.9f, 0.9f, 1.4f, 0.72f, 0.04f), Color{170, 130, 90});
  appendLegs(&m, 3.9f, 1.9f, 0.9f, 1.4f, 0.72f, 0.06f, Color{120, 90, 60});
  appendChair(&m, 3.6f, 1.0f, -1.0f, Color{80, 120, 90});
  appendChair(&m, 4.2f, 1.0f, -1.0f, Color{80, 120, 90});
  appendChair(&m, 3.6f, 2.8f, 1.0f, Color{80, 120, 90});
  appendChair(&m, 4.2f, 2.8f, 1.0f, Color{80, 120, 90});
  // Floor lamp and plant beside the sofa.
  appendCylinder(&m, Vector3f(0.6f, L - 0.5f, 0.0f), Vector3f(0, 0, 0.03f), 0.2f, 24, Color{50, 50, 50});
  appendCylinder(&m, Vector3f(0.6f, L - 0.5f, 0.03f), Vector3f(0, 0, 1.45f), 0.02f, 12, Color{50, 50, 50});
  appendCone(&m, Vector3f(0.6f, L - 0.5f, 1.3f), Vector3f(0, 0, 0.4f), 0.25f, 24, Color{240, 220, 160});
  appendCylinder(&m, Vector3f(4.3f, L - 0.5f, 0.0f), Vector3f(0, 0, 0.4f), 0.2f, 20, Color{170, 90, 60});
  appendSphere(&m, Vector3f(4.3f, L - 0.5f, 0.75f), 0.38f, 10, 16, Color{60, 130, 50});
  // Pictures on the walls and a window frame.
  appendBox(&m, box(W - 0.03f, 3.0f, 1.2f, W, 4.2f, 2.0f), Color{60, 90, 150});
  appendBox(&m, box(1.5f, L - 0.03f, 1.3f, 2.4f, L, 1.9f), Color{200, 150, 60});
  appendBox(&m, box(2.7f, L - 0.03f, 1.2f, 3.5f, L, 2.1f), Color{90, 150, 120});
  appendBox(&m, box(0.0f, 4.0f, 0.9f, 0.03f, 5.6f, 2.2f), Color{220, 230, 240});

  scene.loop_waypoints = {Vector3d(1.2, 1.3, 1.3), Vector3d(3.8, 1.3, 1.4),
                          Vector3d(3.8, 5.0, 1.3), Vector3d(1.2, 5.0, 1.4)};
  scene.orbit_centre = Vector3d(2.5, 3.4, 1.4);
  scene.orbit_radius = 1.4;
  scene.orbit_look_at = Vector3d(2.5, 3.4, 0.6);
  scene.survey_min = Eigen::Vector2d(1.0, 1.0);
  scene.survey_max = Eigen::Vector2d(4.0, 5.4);
  scene.survey_height = 1.6;
  scene.survey_spacing = 1.1;
  scene.eight_centre = Vector3d(2.5, 3.25, 1.3);
  scene.eight_half_x = 1.4;
  scene.eight_half_y = 1.0;
  scene.motion.speed_mps = 0.5;
  scene.motion.turn_radius_m = 0.5;
  scene.motion.pitch_down_rad = 0.25;
  scene.motion.max_bank_rad = 0.1;
  scene.depth_max_m = 6.0;
  scene.texture_wavelength_m = 0.3;
  return scene;
}

BuiltinScene makeIndustrialHall() {
  BuiltinScene scene;
  scene.name = "hall";
  scene.description = "industrial hall 40 x 20 x 10 m with pipes, tanks and crates";
  Mesh& m = scene.mesh;
  const float W = 40.0f, D = 20.0f, H = 10.0f;
  appendInteriorShell(&m, W, D, H,
                      {Color{120, 120, 115}, Color{170, 170, 175}, Color{160, 150, 130},
                       Color{150, 160, 165}, Color{165, 140, 125}, Color{140, 150, 130}},
                      2.0f);
  // Columns along both long walls and roof beams across.
  const Color steel{90, 100, 120};
  for (float x = 4.0f; x < W; x += 8.0f) {
    appendBox(&m, boxAt(x, 0.3f, 0.5f, 0.5f, 0.0f, H), steel);
    appendBox(&m, boxAt(x, D - 0.3f, 0.5f, 0.5f, 0.0f, H), steel);
    appendBox(&m, box(x - 0.2f, 0.55f, H - 0.8f, x + 0.2f, D - 0.55f, H - 0.2f), shade(steel, 0.9f));
  }
  // Pipe rack along the wall y = 0: three pipes with elbows down to the floor at one end.
  const Color pipe_colors[3] = {Color{200, 160, 40}, Color{60, 120, 180}, Color{170, 60, 50}};
  for (int i = 0; i < 3; ++i) {
    const float z = 6.0f + 0.7f * i, y = 1.2f + 0.1f * i, r = 0.15f + 0.05f * i;
    appendCylinder(&m, Vector3f(2.0f, y, z), Vector3f(33.0f, 0, 0), r, 20, pipe_colors[i]);
    const float bend = 0.6f;
    appendPipeBend(&m, Vector3f(35.0f, y, z - bend), Vector3f(0, 0, 1), Vector3f(1, 0, 0), bend, r,
                   kPi / 2, 8, 20, pipe_colors[i]);
    appendCylinder(&m, Vector3f(35.0f + bend, y, z - bend), Vector3f(0, 0, -(z - bend - 0.3f)), r,
                   20, pipe_colors[i]);
  }
  for (float x = 6.0f; x < 36.0f; x += 6.0f) {  // rack supports
    appendBox(&m, box(x - 0.1f, 0.6f, 0.0f, x + 0.1f, 0.8f, 7.8f), steel);
    appendBox(&m, box(x - 0.1f, 0.6f, 5.7f, x + 0.1f, 1.8f, 5.8f), steel);
  }
  // Four tanks with conical tops along the wall y = D, joined by a header pipe.
  const Color tank_colors[4] = {Color{190, 190, 180}, Color{150, 170, 150}, Color{190, 190, 180},
                                Color{170, 150, 130}};
  const float tank_x[4] = {8.0f, 14.0f, 26.0f, 32.0f};
  for (int i = 0; i < 4; ++i) {
    appendCylinder(&m, Vector3f(tank_x[i], 15.5f, 0.0f), Vector3f(0, 0, 5.5f), 1.6f, 48, tank_colors[i]);
    appendCone(&m, Vector3f(tank_x[i], 15.5f, 5.5f), Vector3f(0, 0, 1.0f), 1.6f, 48, shade(tank_colors[i], 0.85f));
    appendCylinder(&m, Vector3f(tank_x[i], 15.5f, 6.5f), Vector3f(0, 0, 1.0f), 0.12f, 16, pipe_colors[1]);
    appendBox(&m, boxAt(tank_x[i], 13.85f, 0.6f, 0.12f, 0.0f, 4.5f), Color{60, 60, 60});  // ladder
  }
  appendCylinder(&m, Vector3f(6.0f, 15.5f, 7.5f), Vector3f(28.0f, 0, 0), 0.14f, 16, pipe_colors[1]);
  // Crates and pallets.
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  const float stacks[5][2] = {{3.0f, 5.0f}, {3.0f, 7.5f}, {37.0f, 6.0f}, {20.0f, 16.5f}, {37.0f, 9.0f}};
  for (const auto& s : stacks) {
    const int levels = 1 + static_cast<int>(3 * unit(rng));
    for (int k = 0; k < levels; ++k) {
      const Color c{static_cast<uint8_t>(140 + 60 * unit(rng)), static_cast<uint8_t>(100 + 40 * unit(rng)),
                    static_cast<uint8_t>(50 + 30 * unit(rng))};
      appendBox(&m, boxAt(s[0], s[1], 1.2f, 1.2f, 0.15f + 1.2f * k, 1.15f), c);
    }
    appendBox(&m, boxAt(s[0], s[1], 1.3f, 1.3f, 0.0f, 0.15f), Color{150, 120, 80});
  }
  // Mezzanine along the wall x = W with four legs and a railing.
  appendBox(&m, box(W - 4.0f, 3.0f, 3.8f, W - 0.05f, 11.0f, 4.0f), Color{100, 110, 100});
  for (float y : {3.2f, 10.8f}) {
    appendBox(&m, boxAt(W - 3.8f, y, 0.25f, 0.25f, 0.0f, 3.8f), steel);
  }
  appendBox(&m, box(W - 4.05f, 3.0f, 4.0f, W - 3.95f, 11.0f, 5.0f), Color{220, 180, 30});

  scene.loop_waypoints = {Vector3d(6, 5, 2.5), Vector3d(34, 5, 3.0), Vector3d(34, 11, 3.5),
                          Vector3d(20, 11.5, 3.0), Vector3d(6, 11, 2.5)};
  scene.orbit_centre = Vector3d(20, 9, 4.0);
  scene.orbit_radius = 6.0;
  scene.orbit_look_at = Vector3d(20, 10, 2.0);
  scene.survey_min = Eigen::Vector2d(5, 4);
  scene.survey_max = Eigen::Vector2d(35, 12);
  scene.survey_height = 4.5;
  scene.survey_spacing = 4.0;
  scene.eight_centre = Vector3d(20, 8.5, 3.0);
  scene.eight_half_x = 12.0;
  scene.eight_half_y = 3.5;
  scene.motion.speed_mps = 1.5;
  scene.motion.turn_radius_m = 2.0;
  scene.motion.pitch_down_rad = 0.15;
  scene.depth_max_m = 15.0;
  scene.texture_wavelength_m = 0.8;
  return scene;
}

BuiltinScene makeTown() {
  BuiltinScene scene;
  scene.name = "town";
  scene.description = "small town 266 x 266 m: street grid, house fronts on both sides, trees";
  Mesh& m = scene.mesh;
  const float spacing = 70.0f, street = 12.0f;
  const int lines = 4;  // street centre lines at 0, 70, 140, 210 in x and y
  const float lo = -spacing * 0.4f, hi = spacing * (lines - 1) + spacing * 0.4f;
  appendQuad(&m, Vector3f(lo, lo, -0.02f), Vector3f(hi - lo, 0, 0), Vector3f(0, hi - lo, 0),
             Color{110, 130, 90}, 8, 8);
  for (int i = 0; i < lines; ++i) {
    const float c = spacing * i;
    appendQuad(&m, Vector3f(lo, c - street / 2, 0.0f), Vector3f(hi - lo, 0, 0), Vector3f(0, street, 0),
               Color{85, 85, 90}, 24, 1);
    appendQuad(&m, Vector3f(c - street / 2, lo, 0.01f), Vector3f(street, 0, 0), Vector3f(0, hi - lo, 0),
               Color{90, 88, 92}, 1, 24);
  }
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  const Color facades[6] = {Color{200, 180, 150}, Color{180, 120, 100}, Color{220, 210, 190},
                            Color{150, 160, 170}, Color{190, 170, 120}, Color{170, 140, 150}};
  const Color window{50, 60, 80};
  // Houses line every block's four sides, fronts facing the street.
  auto add_house = [&](float along, float offset, float width, float depth, float height,
                       bool x_street, float street_c, float side) {
    // Footprint in (u: along the street, w: away from it).
    const float w0 = street_c + side * offset, w1 = w0 + side * depth;
    const float u0 = along, u1 = along + width;
    const AlignedBox3f footprint =
        x_street ? box(u0, std::min(w0, w1), 0.0f, u1, std::max(w0, w1), height)
                 : box(std::min(w0, w1), u0, 0.0f, std::max(w0, w1), u1, height);
    const Color facade = facades[static_cast<int>(6 * unit(rng)) % 6];
    appendBox(&m, footprint, facade);
    // Roof: a low pyramid over the footprint (a 4-sided cone rotated by 45 degrees).
    const Vector3f centre = footprint.center();
    const float half_diag = 0.5f * std::sqrt(width * width + depth * depth);
    Mesh roof;
    appendCone(&roof, Vector3f(0, 0, 0), Vector3f(0, 0, 2.5f), half_diag, 4, Color{120, 60, 50});
    // Stretch the unit pyramid to the footprint: scale x and y.
    const float sx = footprint.sizes().x() / (half_diag * std::sqrt(2.0f));
    const float sy = footprint.sizes().y() / (half_diag * std::sqrt(2.0f));
    const Eigen::Matrix3f rot = Eigen::AngleAxisf(kPi / 4, Vector3f::UnitZ()).toRotationMatrix();
    for (Vector3f& v : roof.vertices) {
      v = rot * v;
      v = Vector3f(v.x() * sx, v.y() * sy, v.z()) + Vector3f(centre.x(), centre.y(), height);
    }
    m.append(roof);
    // Windows: dark boxes protruding 5 cm from the street-facing front, per floor.
    const float front = w0;
    for (float z = 1.0f; z + 1.6f < height; z += 3.0f) {
      for (float u = u0 + 1.0f; u + 1.6f < u1 - 0.5f; u += 2.6f) {
        const float f0 = front - side * 0.05f, f1 = front;
        const AlignedBox3f pane = x_street ? box(u, std::min(f0, f1), z, u + 1.2f, std::max(f0, f1), z + 1.5f)
                                           : box(std::min(f0, f1), u, z, std::max(f0, f1), u + 1.2f, z + 1.5f);
        appendBox(&m, pane, window);
      }
    }
  };
  // Blocks -1 .. lines-1 in x and y: the outer ones get houses only along the border
  // street they face, so every street has houses on both sides.
  for (int bx = -1; bx < lines; ++bx) {
    for (int by = -1; by < lines; ++by) {
      const float x0 = spacing * bx, y0 = spacing * by;
      const bool inner_x = bx >= 0 && bx + 1 < lines, inner_y = by >= 0 && by + 1 < lines;
      // Along the streets y = y0 (houses to +y) and y = y0 + spacing (houses to -y).
      for (int side = 0; side < 2 && inner_x; ++side) {
        if ((side == 0 && by < 0) || (side == 1 && by + 1 >= lines)) continue;
        const float street_c = side == 0 ? y0 : y0 + spacing;
        const float dir = side == 0 ? 1.0f : -1.0f;
        float u = x0 + street / 2 + 4.0f;
        while (true) {
          const float width = 8.0f + 6.0f * unit(rng);
          if (u + width > x0 + spacing - street / 2 - 4.0f) break;
          add_house(u, street / 2 + 3.0f, width, 8.0f + 3.0f * unit(rng), 5.0f + 7.0f * unit(rng),
                    true, street_c, dir);
          u += width + 1.5f + 2.0f * unit(rng);
        }
      }
      // Along the streets x = x0 (houses to +x) and x = x0 + spacing (to -x), shorter rows
      // that leave the corners to the x-street houses.
      for (int side = 0; side < 2 && inner_y; ++side) {
        if ((side == 0 && bx < 0) || (side == 1 && bx + 1 >= lines)) continue;
        const float street_c = side == 0 ? x0 : x0 + spacing;
        const float dir = side == 0 ? 1.0f : -1.0f;
        float u = y0 + street / 2 + 18.0f;
        while (true) {
          const float width = 8.0f + 5.0f * unit(rng);
          if (u + width > y0 + spacing - street / 2 - 18.0f) break;
          add_house(u, street / 2 + 3.0f, width, 9.0f, 5.0f + 8.0f * unit(rng), false, street_c, dir);
          u += width + 2.0f + 2.0f * unit(rng);
        }
      }
    }
  }
  // Trees along the pavements of the streets x = c, every 14 m, both sides.
  for (int i = 0; i < lines; ++i) {
    for (float y = lo + 10.0f; y < hi - 10.0f; y += 14.0f) {
      const float to_crossing = std::abs(y - spacing * std::round(y / spacing));
      if (to_crossing < street / 2 + 4.0f) continue;  // keep crossings clear
      for (float side : {-1.0f, 1.0f}) {
        const float x = spacing * i + side * (street / 2 + 1.2f);
        const float h = 2.5f + 1.5f * unit(rng);
        appendCylinder(&m, Vector3f(x, y, 0.0f), Vector3f(0, 0, h), 0.2f, 8, Color{90, 65, 40});
        appendSphere(&m, Vector3f(x, y, h + 1.2f), 1.6f + 0.6f * unit(rng), 6, 10,
                     Color{static_cast<uint8_t>(50 + 40 * unit(rng)), static_cast<uint8_t>(110 + 50 * unit(rng)), 50});
      }
    }
  }

  scene.loop_waypoints = {Vector3d(0, 0, 1.6), Vector3d(140, 0, 1.6), Vector3d(140, 140, 1.6),
                          Vector3d(70, 140, 1.6), Vector3d(70, 70, 1.6), Vector3d(0, 70, 1.6)};
  // 1260 m a lap. The block loop east of x = 70 (420 m), then east again along y = 0 into
  // it (closure 1), north to the edge of the grid, west, south, east along y = 140, south,
  // and west along y = 70 back into the block loop (closure 2, 630 m after leaving it).
  scene.two_loop_waypoints = {
      Vector3d(70, 0, 1.6),    Vector3d(210, 0, 1.6),   Vector3d(210, 70, 1.6),
      Vector3d(70, 70, 1.6),   Vector3d(70, 0, 1.6),    Vector3d(140, 0, 1.6),
      Vector3d(140, 210, 1.6), Vector3d(0, 210, 1.6),   Vector3d(0, 140, 1.6),
      Vector3d(140, 140, 1.6), Vector3d(140, 70, 1.6),  Vector3d(70, 70, 1.6)};
  // East along y = 0 from the crossing at x = 0, left at (70, 0), north to y = 60: 130 m
  // between the waypoints. A 22 m corner arc turns 90 degrees in 35 m, 2.9 degrees a frame at
  // 11 m/s and 10 Hz, and keeps 2 m off the corner's tree and house.
  scene.street_turn_waypoints = {Vector3d(0, 0, 1.6), Vector3d(70, 0, 1.6), Vector3d(70, 60, 1.6)};
  scene.street_turn_speed_mps = 11.0;
  scene.street_turn_radius_m = 22.0;
  scene.street_turn_ease_m = 10.0;  // a driver eases into and out of the corner over ~1 s
  scene.orbit_centre = Vector3d(105, 105, 12.0);
  scene.orbit_radius = 35.0;
  scene.orbit_look_at = Vector3d(105, 105, 0.0);
  scene.survey_min = Eigen::Vector2d(0, 0);
  scene.survey_max = Eigen::Vector2d(210, 210);
  scene.survey_height = 30.0;
  scene.survey_spacing = 35.0;
  scene.eight_centre = Vector3d(105, 105, 20.0);
  scene.eight_half_x = 70.0;
  scene.eight_half_y = 35.0;
  scene.motion.speed_mps = 8.0;
  // 8 m/s round a 12 m radius is 5.3 m/s^2 (0.54 g) of lateral acceleration, 38 deg/s of
  // yaw: a brisk car. The former 6 m radius meant 1.1 g, beyond any tyre's grip.
  scene.motion.turn_radius_m = 12.0;
  scene.motion.pitch_down_rad = 0.0;
  scene.motion.max_bank_rad = 0.0;
  scene.motion.accel_time_s = 3.0;
  scene.depth_max_m = 25.0;
  scene.texture_wavelength_m = 0.5;
  return scene;
}

TrajectoryKind parseTrajectoryKind(const std::string& text) {
  if (text == "loop") return TrajectoryKind::kLoop;
  if (text == "orbit") return TrajectoryKind::kOrbit;
  if (text == "lawnmower" || text == "lawn-mower") return TrajectoryKind::kLawnMower;
  if (text == "figure-eight" || text == "figure8") return TrajectoryKind::kFigureEight;
  if (text == "two-loops") return TrajectoryKind::kTwoLoops;
  if (text == "street-turn") return TrajectoryKind::kStreetTurn;
  throw std::invalid_argument(
      "unknown trajectory '" + text +
      "' (known: loop, orbit, lawnmower, figure-eight, two-loops, street-turn)");
}

StampedTrajectory makeSceneTrajectory(const BuiltinScene& scene, TrajectoryKind kind,
                                      double rate_hz, int laps) {
  MotionProfile motion = scene.motion;
  motion.rate_hz = rate_hz;
  switch (kind) {
    case TrajectoryKind::kLoop:
      return followPath(scene.loop_waypoints, true, laps, motion);
    case TrajectoryKind::kOrbit:
      return followPath(orbitWaypoints(scene.orbit_centre, scene.orbit_radius), true, laps, motion,
                        scene.orbit_look_at);
    case TrajectoryKind::kLawnMower:
      motion.pitch_down_rad = std::max(motion.pitch_down_rad, 0.6);  // a survey looks down
      return followPath(lawnMowerWaypoints(scene.survey_min, scene.survey_max,
                                           scene.survey_height, scene.survey_spacing),
                        false, 1, motion);
    case TrajectoryKind::kFigureEight:
      return followPath(figureEightWaypoints(scene.eight_centre, scene.eight_half_x,
                                             scene.eight_half_y),
                        true, laps, motion);
    case TrajectoryKind::kTwoLoops:
      if (scene.two_loop_waypoints.empty()) {
        throw std::invalid_argument("makeSceneTrajectory: scene '" + scene.name +
                                    "' has no two-loops route (the town has one)");
      }
      return followPath(scene.two_loop_waypoints, true, laps, motion);
    case TrajectoryKind::kStreetTurn:
      if (scene.street_turn_waypoints.empty()) {
        throw std::invalid_argument("makeSceneTrajectory: scene '" + scene.name +
                                    "' has no street-turn route (the town has one)");
      }
      motion.speed_mps = scene.street_turn_speed_mps;
      motion.turn_radius_m = scene.street_turn_radius_m;
      motion.arc_step_deg = 0.25;  // a car's heading turns smoothly, frame to frame
      motion.ease_m = scene.street_turn_ease_m;
      return followPath(scene.street_turn_waypoints, false, 1, motion);
  }
  throw std::invalid_argument("makeSceneTrajectory: unknown kind");
}

}  // namespace cblox
