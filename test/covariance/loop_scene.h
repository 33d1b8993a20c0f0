#pragma once

// Large synthetic BA scenes with a closed loop for the covariance tests and benchmark:
// keyframes on a circle travelled `laps` times (so every place is revisited), cameras
// looking outwards at points 3-8 m away; each landmark is seen by a short run of
// consecutive keyframes around the one it was created from and, with revisit_probability,
// by keyframes of another lap (loop edges in the reduced camera matrix, as in a real SLAM
// map). Observations are exact (the true state is the BA solution); keyframe 0 is fixed.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <random>
#include <vector>

#include "test/optimization/synthetic_scenes.h"

namespace cblox::test {

struct LoopSceneOptions {
  int keyframes = 50;
  int landmarks_per_keyframe = 50;  ///< landmarks = keyframes * this
  int laps = 2;
  double step_m = 0.3;  ///< distance between consecutive keyframes
  int min_observers = 3;
  int max_observers = 8;
  double revisit_probability = 0.3;  ///< chance that a landmark is seen again on another lap
  double mono_fraction = 0.25;
  std::uint32_t seed = 1;
};

inline BaScene makeLoopBaScene(const LoopSceneOptions& o) {
  BaScene scene;
  scene.problem.camera = syntheticCamera();
  const StereoCameraModel& cam = scene.problem.camera;
  std::mt19937 rng(o.seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const int N = o.keyframes;
  const double radius = N * o.step_m / (2.0 * std::numbers::pi * o.laps);
  std::vector<Transformationd> T_G_C(N);
  for (int k = 0; k < N; ++k) {
    const double theta = 2.0 * std::numbers::pi * o.laps * k / N;
    const double lap = static_cast<double>(k) * o.laps / N;  // 0 .. laps
    const double r = radius + 0.15 * lap;
    const Eigen::Vector3d c(r * std::cos(theta), r * std::sin(theta), 0.1 * lap);
    const Eigen::Vector3d z(std::cos(theta), std::sin(theta), 0.0);  // outwards
    const Eigen::Vector3d y(0.0, 0.0, -1.0);
    Eigen::Matrix3d R;
    R << y.cross(z), y, z;
    R = Eigen::AngleAxisd(0.05 * std::sin(0.7 * k), Eigen::Vector3d::UnitZ()) * R;
    T_G_C[k] = Transformationd(R, c);
    scene.T_C_G_true.push_back(T_G_C[k].inverse());
    scene.problem.keyframes.push_back(
        BaKeyframe{static_cast<std::uint64_t>(100 + k), scene.T_C_G_true[k], k == 0});
  }

  auto project = [&](int k, const Eigen::Vector3d& p, double* u, double* v, double* z) {
    const Eigen::Vector3d p_C = scene.T_C_G_true[k] * p;
    *z = p_C.z();
    if (*z < 0.5) return false;
    *u = cam.fx * p_C.x() / p_C.z() + cam.cx;
    *v = cam.fy * p_C.y() / p_C.z() + cam.cy;
    return *u >= 10 && *u <= scene.width - 10 && *v >= 10 && *v <= scene.height - 10;
  };

  const int window = 10;
  const int lap_length = std::max(1, N / o.laps);
  const int wanted = N * o.landmarks_per_keyframe;
  std::uniform_int_distribution<int> keyframe_of(0, N - 1);
  std::uniform_int_distribution<int> observers_of(o.min_observers, o.max_observers);
  std::uniform_int_distribution<int> octave_of(0, 3);
  std::vector<int> local, far;
  while (static_cast<int>(scene.p_G_true.size()) < wanted) {
    const int k0 = keyframe_of(rng);
    const double depth = 3.0 + 5.0 * unit(rng);
    const double u0 = 20.0 + (scene.width - 40.0) * unit(rng);
    const double v0 = 20.0 + (scene.height - 40.0) * unit(rng);
    const Eigen::Vector3d p = T_G_C[k0] * Eigen::Vector3d((u0 - cam.cx) * depth / cam.fx,
                                                          (v0 - cam.cy) * depth / cam.fy, depth);
    // Visible keyframes of this visit (by index distance) and of the other laps.
    local.clear();
    far.clear();
    for (int s = 0; s < o.laps; ++s) {
      for (int d = -window; d <= window; ++d) {
        const int k = ((k0 + s * lap_length + d) % N + N) % N;
        double u = 0.0, v = 0.0, z = 0.0;
        if (!project(k, p, &u, &v, &z)) continue;
        std::vector<int>& list = s == 0 ? local : far;
        if (std::find(local.begin(), local.end(), k) == local.end() &&
            std::find(far.begin(), far.end(), k) == far.end()) {
          list.push_back(k);
        }
      }
    }
    const int m = observers_of(rng);
    const int m_far = (!far.empty() && unit(rng) < o.revisit_probability)
                          ? std::min<int>({2, static_cast<int>(far.size()), m - 1})
                          : 0;
    // Closest-in-index keyframes of this visit; a contiguous run of another visit.
    auto cyclic = [N](int a, int b) {
      const int d = std::abs(a - b) % N;
      return std::min(d, N - d);
    };
    std::sort(local.begin(), local.end(),
              [&](int a, int b) { return cyclic(a, k0) < cyclic(b, k0); });
    local.resize(std::min<size_t>(local.size(), m - m_far));
    if (m_far > 0) {
      const int k1 = far[std::uniform_int_distribution<int>(0, far.size() - 1)(rng)];
      std::sort(far.begin(), far.end(),
                [&](int a, int b) { return cyclic(a, k1) < cyclic(b, k1); });
      local.insert(local.end(), far.begin(), far.begin() + m_far);
    }
    std::vector<BaObservation> observations;
    bool any_stereo = false;
    for (const int k : local) {
      BaObservation obs;
      double u = 0.0, v = 0.0, z = 0.0;
      project(k, p, &u, &v, &z);
      obs.keyframe = k;
      obs.landmark = static_cast<int>(scene.p_G_true.size());
      const double scale = std::pow(1.2, octave_of(rng));
      obs.inv_sigma2 = 1.0 / (scale * scale);
      obs.u = u;
      obs.v = v;
      const double u_right = u - cam.bf / z;
      const bool stereo = unit(rng) >= o.mono_fraction && u_right >= 0.0;
      obs.u_right = stereo ? u_right : -1.0;
      any_stereo = any_stereo || stereo;
      observations.push_back(obs);
    }
    if (observations.size() < 2 || !any_stereo) continue;
    scene.problem.landmarks.push_back(
        BaLandmark{static_cast<std::uint64_t>(1000000 + scene.p_G_true.size()), p});
    scene.p_G_true.push_back(p);
    scene.problem.observations.insert(scene.problem.observations.end(), observations.begin(),
                                      observations.end());
  }
  return scene;
}

}  // namespace cblox::test
