#include "drivers/synthetic/primitives.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/Geometry>

namespace cblox {
namespace {

using Eigen::Vector2d;
using Eigen::Vector3d;

// Keeps the smallest root in (0, t_max]. Returns true if `root` was accepted.
bool takeIfCloser(double root, double t_max, double* best) {
  if (root > 0.0 && root <= t_max && root < *best) {
    *best = root;
    return true;
  }
  return false;
}

// Roots of |o + lambda * d|^2 = r^2 for a unit d (o relative to the centre), written into
// *near <= *far. Uses the closest-approach form and Vieta's formula to avoid cancellation.
// Returns false if the line misses the circle/sphere.
template <int N>
bool solveUnitQuadratic(const Eigen::Matrix<double, N, 1>& o, const Eigen::Matrix<double, N, 1>& d,
                        double r, double* near, double* far) {
  const double tca = -d.dot(o);  // parameter of the closest approach
  const Eigen::Matrix<double, N, 1> perp = o + tca * d;
  const double disc = r * r - perp.squaredNorm();
  if (disc < 0.0) return false;
  const double h = std::sqrt(disc);
  const double c = o.squaredNorm() - r * r;  // product of the roots
  const double q = tca >= 0.0 ? tca + h : tca - h;
  if (q == 0.0) {
    *near = *far = 0.0;
    return true;
  }
  const double r1 = q;
  const double r2 = c / q;
  *near = std::min(r1, r2);
  *far = std::max(r1, r2);
  return true;
}

// Ray against the surface of an axis-aligned box (from outside or inside).
bool intersectBox(const Vector3d& lo, const Vector3d& hi, const Vector3d& o, const Vector3d& d,
                  double t_max, double* t) {
  double t_near = -std::numeric_limits<double>::infinity();
  double t_far = std::numeric_limits<double>::infinity();
  for (int i = 0; i < 3; ++i) {
    if (d[i] == 0.0) {
      if (o[i] < lo[i] || o[i] > hi[i]) return false;
      continue;
    }
    double t1 = (lo[i] - o[i]) / d[i];
    double t2 = (hi[i] - o[i]) / d[i];
    if (t1 > t2) std::swap(t1, t2);
    t_near = std::max(t_near, t1);
    t_far = std::min(t_far, t2);
  }
  if (t_near > t_far) return false;
  double best = std::numeric_limits<double>::infinity();
  if (!takeIfCloser(t_near, t_max, &best)) takeIfCloser(t_far, t_max, &best);
  if (!std::isfinite(best)) return false;
  *t = best;
  return true;
}

// Signed distance to a solid axis-aligned box (negative inside). Exact.
double boxSignedDistance(const Vector3d& lo, const Vector3d& hi, const Vector3d& p) {
  const Vector3d centre = 0.5 * (lo + hi);
  const Vector3d half = 0.5 * (hi - lo);
  const Vector3d q = (p - centre).cwiseAbs() - half;
  return q.cwiseMax(0.0).norm() + std::min(q.maxCoeff(), 0.0);
}

// Checker coordinates on the face of an axis-aligned box closest to p.
Vector2d boxFaceUv(const Vector3d& lo, const Vector3d& hi, const Vector3d& p) {
  const Vector3d centre = 0.5 * (lo + hi);
  const Vector3d half = 0.5 * (hi - lo);
  const Vector3d q = ((p - centre).cwiseAbs() - half).cwiseAbs();
  int axis = 0;
  q.minCoeff(&axis);  // the face whose plane p is closest to
  switch (axis) {
    case 0:
      return {p.y(), p.z()};
    case 1:
      return {p.x(), p.z()};
    default:
      return {p.x(), p.y()};
  }
}

// Any unit vector perpendicular to the unit vector n (deterministic).
Vector3d perpendicular(const Vector3d& n) {
  const Vector3d helper = std::abs(n.x()) < 0.9 ? Vector3d::UnitX() : Vector3d::UnitY();
  return n.cross(helper).normalized();
}

bool allFinite(const Vector3d& v) { return v.allFinite(); }

// --- per-primitive implementations -------------------------------------------------------

bool intersectImpl(const Plane& s, const Vector3d& o, const Vector3d& d, double t_max, double* t) {
  const double denom = s.normal.dot(d);
  if (denom == 0.0) return false;
  const double root = s.normal.dot(s.point - o) / denom;
  if (!(root > 0.0 && root <= t_max)) return false;
  *t = root;
  return true;
}

bool intersectImpl(const Sphere& s, const Vector3d& o, const Vector3d& d, double t_max, double* t) {
  double near = 0.0, far = 0.0;
  if (!solveUnitQuadratic<3>(o - s.centre, d, s.radius, &near, &far)) return false;
  double best = std::numeric_limits<double>::infinity();
  if (!takeIfCloser(near, t_max, &best)) takeIfCloser(far, t_max, &best);
  if (!std::isfinite(best)) return false;
  *t = best;
  return true;
}

bool intersectImpl(const SolidBox& s, const Vector3d& o, const Vector3d& d, double t_max,
                   double* t) {
  return intersectBox(s.min_corner, s.max_corner, o, d, t_max, t);
}

bool intersectImpl(const Room& s, const Vector3d& o, const Vector3d& d, double t_max, double* t) {
  return intersectBox(s.min_corner, s.max_corner, o, d, t_max, t);
}

bool intersectImpl(const Cylinder& s, const Vector3d& o, const Vector3d& d, double t_max,
                   double* t) {
  double best = std::numeric_limits<double>::infinity();
  // Side: solve in the xy plane with the unit horizontal direction, then rescale.
  const Vector2d d_xy(d.x(), d.y());
  const double s_xy = d_xy.norm();
  if (s_xy > 0.0) {
    const Vector2d o_xy(o.x() - s.axis_x, o.y() - s.axis_y);
    double near = 0.0, far = 0.0;
    if (solveUnitQuadratic<2>(o_xy, d_xy / s_xy, s.radius, &near, &far)) {
      for (const double lambda : {near, far}) {
        const double root = lambda / s_xy;
        const double z = o.z() + root * d.z();
        if (z >= s.z_min && z <= s.z_max) takeIfCloser(root, t_max, &best);
      }
    }
  }
  // Caps.
  if (d.z() != 0.0) {
    for (const double z_cap : {s.z_min, s.z_max}) {
      const double root = (z_cap - o.z()) / d.z();
      const double x = o.x() + root * d.x() - s.axis_x;
      const double y = o.y() + root * d.y() - s.axis_y;
      if (x * x + y * y <= s.radius * s.radius) takeIfCloser(root, t_max, &best);
    }
  }
  if (!std::isfinite(best)) return false;
  *t = best;
  return true;
}

double signedDistanceImpl(const Plane& s, const Vector3d& p) { return s.normal.dot(p - s.point); }

double signedDistanceImpl(const Sphere& s, const Vector3d& p) {
  return (p - s.centre).norm() - s.radius;
}

double signedDistanceImpl(const SolidBox& s, const Vector3d& p) {
  return boxSignedDistance(s.min_corner, s.max_corner, p);
}

double signedDistanceImpl(const Room& s, const Vector3d& p) {
  return -boxSignedDistance(s.min_corner, s.max_corner, p);
}

double signedDistanceImpl(const Cylinder& s, const Vector3d& p) {
  const double dr = std::hypot(p.x() - s.axis_x, p.y() - s.axis_y) - s.radius;
  const double dz = std::max(s.z_min - p.z(), p.z() - s.z_max);
  return std::min(std::max(dr, dz), 0.0) + Vector2d(dr, dz).cwiseMax(0.0).norm();
}

Color surfaceColorImpl(const Plane& s, const Vector3d& p) {
  const Vector3d e1 = perpendicular(s.normal);
  const Vector3d e2 = s.normal.cross(e1);
  const Vector3d rel = p - s.point;
  return s.texture.colorAt({rel.dot(e1), rel.dot(e2)});
}

Color surfaceColorImpl(const Sphere& s, const Vector3d& p) {
  const Vector3d v = p - s.centre;
  const double n = v.norm();
  if (n == 0.0) return s.texture.a;
  const double azimuth = std::atan2(v.y(), v.x());
  const double elevation = std::asin(std::clamp(v.z() / n, -1.0, 1.0));
  return s.texture.colorAt({s.radius * azimuth, s.radius * elevation});
}

Color surfaceColorImpl(const SolidBox& s, const Vector3d& p) {
  return s.texture.colorAt(boxFaceUv(s.min_corner, s.max_corner, p));
}

Color surfaceColorImpl(const Room& s, const Vector3d& p) {
  return s.texture.colorAt(boxFaceUv(s.min_corner, s.max_corner, p));
}

Color surfaceColorImpl(const Cylinder& s, const Vector3d& p) {
  const double x = p.x() - s.axis_x;
  const double y = p.y() - s.axis_y;
  const double dr = std::abs(std::hypot(x, y) - s.radius);
  const double dz = std::min(std::abs(p.z() - s.z_min), std::abs(p.z() - s.z_max));
  if (dr <= dz) return s.texture.colorAt({s.radius * std::atan2(y, x), p.z()});
  return s.texture.colorAt({p.x(), p.y()});
}

std::string validateBox(const Vector3d& lo, const Vector3d& hi, const char* what) {
  if (!allFinite(lo) || !allFinite(hi)) return std::string(what) + ": corners must be finite";
  if (!(lo.array() < hi.array()).all()) {
    return std::string(what) + ": min_corner must be below max_corner on every axis";
  }
  return {};
}

std::string validateImpl(const Plane& s) {
  if (!allFinite(s.point) || !allFinite(s.normal)) return "Plane: point and normal must be finite";
  if (!(s.normal.norm() > 1e-12)) return "Plane: normal must be non-zero";
  return {};
}

std::string validateImpl(const Sphere& s) {
  if (!allFinite(s.centre)) return "Sphere: centre must be finite";
  if (!(s.radius > 0.0) || !std::isfinite(s.radius)) return "Sphere: radius must be > 0";
  return {};
}

std::string validateImpl(const SolidBox& s) {
  return validateBox(s.min_corner, s.max_corner, "SolidBox");
}

std::string validateImpl(const Room& s) { return validateBox(s.min_corner, s.max_corner, "Room"); }

std::string validateImpl(const Cylinder& s) {
  if (!std::isfinite(s.axis_x) || !std::isfinite(s.axis_y)) return "Cylinder: axis must be finite";
  if (!(s.radius > 0.0) || !std::isfinite(s.radius)) return "Cylinder: radius must be > 0";
  if (!std::isfinite(s.z_min) || !std::isfinite(s.z_max) || !(s.z_min < s.z_max)) {
    return "Cylinder: need finite z_min < z_max";
  }
  return {};
}

}  // namespace

std::string validate(const Primitive& primitive) {
  return std::visit([](const auto& s) { return validateImpl(s); }, primitive);
}

bool intersect(const Primitive& primitive, const Vector3d& origin, const Vector3d& dir,
               double t_max, double* t) {
  return std::visit([&](const auto& s) { return intersectImpl(s, origin, dir, t_max, t); },
                    primitive);
}

double signedDistance(const Primitive& primitive, const Vector3d& p) {
  return std::visit([&](const auto& s) { return signedDistanceImpl(s, p); }, primitive);
}

Color surfaceColor(const Primitive& primitive, const Vector3d& p) {
  return std::visit([&](const auto& s) { return surfaceColorImpl(s, p); }, primitive);
}

}  // namespace cblox
