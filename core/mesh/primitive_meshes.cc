#include "core/mesh/primitive_meshes.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>
#include <string>

namespace cblox {
namespace {

constexpr float kTwoPi = 6.28318530717958647692f;

/// Appends vertices and triangles to a mesh, keeping vertex colours consistent.
class Appender {
 public:
  explicit Appender(Mesh* mesh) : mesh_(*mesh) {
    if (!mesh_.vertices.empty() && !mesh_.hasColors()) {
      throw std::invalid_argument("primitive_meshes: the mesh has vertices without colours");
    }
  }

  int vertex(const Eigen::Vector3f& p, const Color& color) {
    mesh_.vertices.push_back(p);
    mesh_.colors.push_back(color);
    return static_cast<int>(mesh_.vertices.size() - 1);
  }

  /// Adds triangle (a, b, c), reversed if its normal points against `outward`.
  void triangle(int a, int b, int c, const Eigen::Vector3f& outward) {
    const Eigen::Vector3f& pa = mesh_.vertices[a];
    const Eigen::Vector3f n = (mesh_.vertices[b] - pa).cross(mesh_.vertices[c] - pa);
    if (n.dot(outward) < 0.0f) std::swap(b, c);
    mesh_.triangles.emplace_back(a, b, c);
  }

  /// Adds quad (a, b, c, d) (cyclic order) as two triangles facing `outward`.
  void quad(int a, int b, int c, int d, const Eigen::Vector3f& outward) {
    triangle(a, b, c, outward);
    triangle(a, c, d, outward);
  }

  const Eigen::Vector3f& position(int i) const { return mesh_.vertices[i]; }

 private:
  Mesh& mesh_;
};

void requireAtLeast(int value, int minimum, const char* what) {
  if (value < minimum) {
    throw std::invalid_argument(std::string("primitive_meshes: ") + what + " must be >= " +
                                std::to_string(minimum) + ", got " + std::to_string(value));
  }
}

/// Two unit vectors completing `axis` to a right-handed orthonormal basis.
void orthonormalBasis(const Eigen::Vector3f& axis, Eigen::Vector3f* e1, Eigen::Vector3f* e2) {
  const Eigen::Vector3f a = axis.normalized();
  const Eigen::Vector3f helper =
      std::abs(a.x()) < 0.9f ? Eigen::Vector3f::UnitX() : Eigen::Vector3f::UnitY();
  *e1 = a.cross(helper).normalized();
  *e2 = a.cross(*e1);
}

/// A box from its 8 corners (index bits: 1 = +x, 2 = +y, 4 = +z in the box frame).
void appendBoxCorners(Mesh* mesh, const std::array<Eigen::Vector3f, 8>& corners,
                      const Color& color, bool inward) {
  Appender out(mesh);
  std::array<int, 8> ids;
  Eigen::Vector3f centre = Eigen::Vector3f::Zero();
  for (int i = 0; i < 8; ++i) {
    ids[i] = out.vertex(corners[i], color);
    centre += corners[i] / 8.0f;
  }
  static constexpr int kFaces[6][4] = {{0, 2, 6, 4}, {1, 3, 7, 5}, {0, 1, 5, 4},
                                       {2, 3, 7, 6}, {0, 1, 3, 2}, {4, 5, 7, 6}};
  for (const auto& f : kFaces) {
    const Eigen::Vector3f face_centre =
        (corners[f[0]] + corners[f[1]] + corners[f[2]] + corners[f[3]]) / 4.0f;
    const Eigen::Vector3f outward = inward ? centre - face_centre : face_centre - centre;
    out.quad(ids[f[0]], ids[f[1]], ids[f[2]], ids[f[3]], outward);
  }
}

}  // namespace

void appendQuad(Mesh* mesh, const Eigen::Vector3f& corner, const Eigen::Vector3f& edge_u,
                const Eigen::Vector3f& edge_v, const Color& color, int cells_u, int cells_v) {
  requireAtLeast(cells_u, 1, "cells_u");
  requireAtLeast(cells_v, 1, "cells_v");
  Appender out(mesh);
  const Eigen::Vector3f normal = edge_u.cross(edge_v);
  const int first = static_cast<int>(mesh->vertices.size());
  for (int j = 0; j <= cells_v; ++j) {
    for (int i = 0; i <= cells_u; ++i) {
      out.vertex(corner + edge_u * (static_cast<float>(i) / cells_u) +
                     edge_v * (static_cast<float>(j) / cells_v),
                 color);
    }
  }
  auto id = [&](int i, int j) { return first + j * (cells_u + 1) + i; };
  for (int j = 0; j < cells_v; ++j) {
    for (int i = 0; i < cells_u; ++i) {
      out.quad(id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1), normal);
    }
  }
}

void appendBox(Mesh* mesh, const Eigen::AlignedBox3f& box, const Color& color, bool inward) {
  std::array<Eigen::Vector3f, 8> corners;
  for (int i = 0; i < 8; ++i) {
    corners[i] = Eigen::Vector3f((i & 1) ? box.max().x() : box.min().x(),
                                 (i & 2) ? box.max().y() : box.min().y(),
                                 (i & 4) ? box.max().z() : box.min().z());
  }
  appendBoxCorners(mesh, corners, color, inward);
}

void appendOrientedBox(Mesh* mesh, const Transformation& T_G_B, const Eigen::Vector3f& half,
                       const Color& color) {
  std::array<Eigen::Vector3f, 8> corners;
  for (int i = 0; i < 8; ++i) {
    const Eigen::Vector3f p_B((i & 1) ? half.x() : -half.x(), (i & 2) ? half.y() : -half.y(),
                              (i & 4) ? half.z() : -half.z());
    corners[i] = T_G_B * p_B;
  }
  appendBoxCorners(mesh, corners, color, false);
}

void appendCylinder(Mesh* mesh, const Eigen::Vector3f& base, const Eigen::Vector3f& axis,
                    float radius, int segments, const Color& color) {
  requireAtLeast(segments, 3, "segments");
  Appender out(mesh);
  Eigen::Vector3f e1, e2;
  orthonormalBasis(axis, &e1, &e2);
  const int bottom_centre = out.vertex(base, color);
  const int top_centre = out.vertex(base + axis, color);
  const int first = static_cast<int>(mesh->vertices.size());
  for (int i = 0; i < segments; ++i) {
    const float phi = kTwoPi * static_cast<float>(i) / static_cast<float>(segments);
    const Eigen::Vector3f offset = radius * (std::cos(phi) * e1 + std::sin(phi) * e2);
    out.vertex(base + offset, color);
    out.vertex(base + axis + offset, color);
  }
  for (int i = 0; i < segments; ++i) {
    const int b0 = first + 2 * i, t0 = b0 + 1;
    const int b1 = first + 2 * ((i + 1) % segments), t1 = b1 + 1;
    const Eigen::Vector3f radial = (out.position(b0) + out.position(b1)) * 0.5f - base;
    const Eigen::Vector3f side = radial - radial.dot(axis.normalized()) * axis.normalized();
    out.quad(b0, b1, t1, t0, side);
    out.triangle(bottom_centre, b0, b1, -axis);
    out.triangle(top_centre, t0, t1, axis);
  }
}

void appendCone(Mesh* mesh, const Eigen::Vector3f& base, const Eigen::Vector3f& axis,
                float radius, int segments, const Color& color) {
  requireAtLeast(segments, 3, "segments");
  Appender out(mesh);
  Eigen::Vector3f e1, e2;
  orthonormalBasis(axis, &e1, &e2);
  const int base_centre = out.vertex(base, color);
  const int apex = out.vertex(base + axis, color);
  const int first = static_cast<int>(mesh->vertices.size());
  for (int i = 0; i < segments; ++i) {
    const float phi = kTwoPi * static_cast<float>(i) / static_cast<float>(segments);
    out.vertex(base + radius * (std::cos(phi) * e1 + std::sin(phi) * e2), color);
  }
  for (int i = 0; i < segments; ++i) {
    const int r0 = first + i, r1 = first + (i + 1) % segments;
    const Eigen::Vector3f radial = (out.position(r0) + out.position(r1)) * 0.5f - base;
    out.triangle(apex, r0, r1, radial);
    out.triangle(base_centre, r0, r1, -axis);
  }
}

void appendSphere(Mesh* mesh, const Eigen::Vector3f& centre, float radius, int rings,
                  int segments, const Color& color) {
  requireAtLeast(rings, 2, "rings");
  requireAtLeast(segments, 3, "segments");
  Appender out(mesh);
  const int north = out.vertex(centre + Eigen::Vector3f(0, 0, radius), color);
  const int south = out.vertex(centre - Eigen::Vector3f(0, 0, radius), color);
  const int first = static_cast<int>(mesh->vertices.size());
  for (int r = 1; r < rings; ++r) {
    const float theta = 0.5f * kTwoPi * static_cast<float>(r) / static_cast<float>(rings);
    for (int s = 0; s < segments; ++s) {
      const float phi = kTwoPi * static_cast<float>(s) / static_cast<float>(segments);
      out.vertex(centre + radius * Eigen::Vector3f(std::sin(theta) * std::cos(phi),
                                                   std::sin(theta) * std::sin(phi),
                                                   std::cos(theta)),
                 color);
    }
  }
  auto id = [&](int ring, int s) { return first + (ring - 1) * segments + (s % segments); };
  auto outward = [&](int a, int b, int c) {
    return (out.position(a) + out.position(b) + out.position(c)) / 3.0f - centre;
  };
  for (int s = 0; s < segments; ++s) {
    out.triangle(north, id(1, s), id(1, s + 1), outward(north, id(1, s), id(1, s + 1)));
    out.triangle(south, id(rings - 1, s), id(rings - 1, s + 1),
                 outward(south, id(rings - 1, s), id(rings - 1, s + 1)));
    for (int r = 1; r + 1 < rings; ++r) {
      const int a = id(r, s), b = id(r, s + 1), c = id(r + 1, s + 1), d = id(r + 1, s);
      out.quad(a, b, c, d, outward(a, b, c));
    }
  }
}

void appendPipeBend(Mesh* mesh, const Eigen::Vector3f& centre, const Eigen::Vector3f& u,
                    const Eigen::Vector3f& v, float bend_radius, float tube_radius, float angle,
                    int segments, int tube_segments, const Color& color) {
  requireAtLeast(segments, 1, "segments");
  requireAtLeast(tube_segments, 3, "tube_segments");
  Appender out(mesh);
  const Eigen::Vector3f eu = u.normalized();
  const Eigen::Vector3f ev = (v - v.dot(eu) * eu).normalized();
  const Eigen::Vector3f w = eu.cross(ev);
  const bool closed = angle >= kTwoPi;
  const float sweep = closed ? kTwoPi : angle;
  const int rings = closed ? segments : segments + 1;
  auto ring_centre = [&](int k) {
    const float theta = sweep * static_cast<float>(k) / static_cast<float>(segments);
    return Eigen::Vector3f(centre + bend_radius * (std::cos(theta) * eu + std::sin(theta) * ev));
  };
  const int first = static_cast<int>(mesh->vertices.size());
  for (int k = 0; k < rings; ++k) {
    const Eigen::Vector3f c = ring_centre(k);
    const Eigen::Vector3f radial = (c - centre).normalized();
    for (int s = 0; s < tube_segments; ++s) {
      const float phi = kTwoPi * static_cast<float>(s) / static_cast<float>(tube_segments);
      out.vertex(c + tube_radius * (std::cos(phi) * radial + std::sin(phi) * w), color);
    }
  }
  auto id = [&](int k, int s) {
    return first + (k % rings) * tube_segments + (s % tube_segments);
  };
  for (int k = 0; k < segments; ++k) {
    const Eigen::Vector3f mid = (ring_centre(k) + ring_centre(k + 1)) * 0.5f;
    for (int s = 0; s < tube_segments; ++s) {
      const int a = id(k, s), b = id(k, s + 1), c = id(k + 1, s + 1), d = id(k + 1, s);
      const Eigen::Vector3f centroid = (out.position(a) + out.position(c)) * 0.5f;
      out.quad(a, b, c, d, centroid - mid);
    }
  }
  if (!closed) {
    const Eigen::Vector3f start_tangent = -ev;
    const float theta = sweep;
    const Eigen::Vector3f end_tangent = -std::sin(theta) * eu + std::cos(theta) * ev;
    const int start_centre = out.vertex(ring_centre(0), color);
    const int end_centre = out.vertex(ring_centre(segments), color);
    for (int s = 0; s < tube_segments; ++s) {
      out.triangle(start_centre, id(0, s), id(0, s + 1), start_tangent);
      out.triangle(end_centre, id(segments, s), id(segments, s + 1), end_tangent);
    }
  }
}

}  // namespace cblox
