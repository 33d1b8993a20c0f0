#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "core/geometry/image.h"
#include "core/geometry/pinhole_camera.h"
#include "core/geometry/se3.h"
#include "drivers/synthetic/analytic_scene.h"

namespace cblox {

/// One rendered frame: ground-truth pose and exact depth (camera z, metres; 0 = no hit) and
/// colour. Plain value type.
struct SyntheticFrame {
  int64_t timestamp_ns = 0;
  Transformationd T_G_C;
  DepthImage depth;
  ColorImage color;
};

/// Plays an AnalyticScene along a trajectory as a depth camera: frame i is rendered at pose
/// trajectory[i] with timestamp round(i * 1e9 / rate_hz) ns.
/// Thread-safety: not thread-safe (next() advances a cursor); use one instance per thread.
class SyntheticDepthSource {
 public:
  /// Throws std::invalid_argument if the intrinsics are invalid (see validate()), or rate_hz
  /// or max_range (metres, Euclidean range along a ray) is not > 0 and finite.
  SyntheticDepthSource(AnalyticScene scene, PinholeIntrinsics intrinsics,
                       std::vector<Transformationd> trajectory, double rate_hz, double max_range);

  /// Number of frames (trajectory length). Not thread-safe with next().
  size_t size() const { return trajectory_.size(); }

  /// Index of the frame the next call to next() renders. Not thread-safe with next().
  size_t position() const { return next_index_; }

  /// Renders the next frame into *frame (non-null) and returns true, or returns false
  /// (leaving *frame untouched) once all frames have been delivered. Not thread-safe.
  bool next(SyntheticFrame* frame);

  /// Starts again from the first frame. Not thread-safe.
  void reset() { next_index_ = 0; }

  /// The scene and camera being rendered. Not thread-safe with next().
  const AnalyticScene& scene() const { return scene_; }
  const PinholeCamera& camera() const { return camera_; }

 private:
  AnalyticScene scene_;
  PinholeCamera camera_;
  std::vector<Transformationd> trajectory_;
  double rate_hz_;
  double max_range_;
  size_t next_index_ = 0;
};

}  // namespace cblox
