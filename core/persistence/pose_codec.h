#pragma once

// A rigid transform in the map file formats: 7 little-endian f64, tx ty tz qx qy qz qw.
// Internal to cblox_persistence.

#include "core/geometry/se3.h"
#include "core/persistence/byte_codec.h"

namespace cblox::persistence_detail {

inline void writePose(ByteWriter& w, const Transformationd& T) {
  const Eigen::Vector3d& t = T.translation();
  const Eigen::Quaterniond& q = T.rotation();
  for (const double v : {t.x(), t.y(), t.z(), q.x(), q.y(), q.z(), q.w()}) w.f64(v);
}

/// Reads a pose; false (reader failed, or *T unchanged) when truncated, not finite, or the
/// quaternion's norm is not within [0.5, 2]. A unit quaternion (as writePose writes it: within
/// 1e-9) is kept bit for bit, so a saved pose loads bit-identical; any other is normalised.
inline bool readPose(ByteReader& r, Transformationd* T) {
  double v[7];
  for (double& x : v) r.f64(&x);
  if (!r.ok()) return false;
  const Eigen::Quaterniond q(v[6], v[3], v[4], v[5]);
  const Eigen::Vector3d t(v[0], v[1], v[2]);
  const double norm = Eigen::Vector4d(v[3], v[4], v[5], v[6]).norm();
  if (!t.allFinite() || !std::isfinite(norm) || norm < 0.5 || norm > 2.0) return false;
  *T = std::abs(norm - 1.0) <= 1e-9 ? Transformationd::fromUnitQuaternion(q, t)
                                    : Transformationd(q, t);
  return true;
}

}  // namespace cblox::persistence_detail
