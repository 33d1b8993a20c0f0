#pragma once

#include <algorithm>

#include <Eigen/Core>

namespace cblox {

/// Closest point to p on the triangle (a, b, c), including its edges and corners (Ericson,
/// "Real-Time Collision Detection", 5.1.5: Voronoi regions of the corners and edges, else the
/// face). Exact up to floating-point rounding; a degenerate triangle (collinear corners) gives
/// the closest point on its longest edge's segment set, never NaN. Thread-safe (pure).
inline Eigen::Vector3d closestPointOnTriangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                                              const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  const Eigen::Vector3d ab = b - a;
  const Eigen::Vector3d ac = c - a;
  const Eigen::Vector3d ap = p - a;
  const double d1 = ab.dot(ap);
  const double d2 = ac.dot(ap);
  if (d1 <= 0.0 && d2 <= 0.0) return a;  // corner a

  const Eigen::Vector3d bp = p - b;
  const double d3 = ab.dot(bp);
  const double d4 = ac.dot(bp);
  if (d3 >= 0.0 && d4 <= d3) return b;  // corner b

  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) {  // edge ab
    const double denom = d1 - d3;
    return denom > 0.0 ? Eigen::Vector3d(a + (d1 / denom) * ab) : a;
  }

  const Eigen::Vector3d cp = p - c;
  const double d5 = ab.dot(cp);
  const double d6 = ac.dot(cp);
  if (d6 >= 0.0 && d5 <= d6) return c;  // corner c

  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) {  // edge ac
    const double denom = d2 - d6;
    return denom > 0.0 ? Eigen::Vector3d(a + (d2 / denom) * ac) : a;
  }

  const double va = d3 * d6 - d5 * d4;
  if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0) {  // edge bc
    const double denom = (d4 - d3) + (d5 - d6);
    return denom > 0.0 ? Eigen::Vector3d(b + ((d4 - d3) / denom) * (c - b)) : b;
  }

  const double sum = va + vb + vc;
  if (!(sum > 0.0)) {
    // Degenerate triangle that fell through every region test: take the best edge point.
    auto on_segment = [&p](const Eigen::Vector3d& s, const Eigen::Vector3d& e) {
      const Eigen::Vector3d d = e - s;
      const double len2 = d.squaredNorm();
      const double t = len2 > 0.0 ? std::clamp((p - s).dot(d) / len2, 0.0, 1.0) : 0.0;
      return Eigen::Vector3d(s + t * d);
    };
    Eigen::Vector3d best = on_segment(a, b);
    for (const Eigen::Vector3d& q : {on_segment(b, c), on_segment(c, a)}) {
      if ((q - p).squaredNorm() < (best - p).squaredNorm()) best = q;
    }
    return best;
  }
  const double v = vb / sum;
  const double w = vc / sum;
  return a + ab * v + ac * w;  // inside the face
}

}  // namespace cblox
