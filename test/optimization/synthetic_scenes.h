#pragma once

// Synthetic scenes for the optimization tests and benchmark: BA scenes (keyframes along a
// gently rotating path looking at random points) and single-frame pose scenes, with exact
// (or noisy) observations.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include "core/optimization/bundle_adjustment.h"
#include "core/optimization/pose_optimizer.h"

namespace cblox::test {

struct BaSceneOptions {
  int keyframes = 10;
  int landmarks = 500;
  double step_m = 0.25;              ///< distance between keyframes along x
  double observe_probability = 1.0;  ///< chance that a visible point is observed
  double mono_fraction = 0.25;       ///< chance that an observation is mono
  double pixel_noise = 0.0;          ///< sigma at octave 0, pixels (scaled by 1.2^octave)
  std::uint32_t seed = 1;
};

struct BaScene {
  BundleAdjustmentProblem problem;  ///< true poses and points, observations as made
  std::vector<Transformationd> T_C_G_true;
  std::vector<Eigen::Vector3d> p_G_true;
  int width = 752;
  int height = 480;
};

inline StereoCameraModel syntheticCamera() {
  return StereoCameraModel{450.0, 450.0, 376.0, 240.0, 450.0 * 0.11};
}

/// exp([sigma_t * n_t; sigma_r * n_r]) * T with standard normal n.
inline Transformationd perturbPose(const Transformationd& T, double sigma_t, double sigma_r,
                                   std::mt19937& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  Eigen::Matrix<double, 6, 1> xi;
  for (int k = 0; k < 6; ++k) xi[k] = n(rng) * (k < 3 ? sigma_t : sigma_r);
  return Transformationd::exp(xi) * T;
}

/// Norm of log(A * B^-1): metres and radians in one number.
inline double poseDistance(const Transformationd& A, const Transformationd& B) {
  return (A * B.inverse()).log().norm();
}

inline BaScene makeBaScene(const BaSceneOptions& o) {
  BaScene scene;
  scene.problem.camera = syntheticCamera();
  const StereoCameraModel& cam = scene.problem.camera;
  std::mt19937 rng(o.seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::normal_distribution<double> normal(0.0, 1.0);
  std::uniform_int_distribution<int> octave_of(0, 3);

  for (int k = 0; k < o.keyframes; ++k) {
    const Eigen::Vector3d c(k * o.step_m, 0.05 * std::sin(0.9 * k), 0.04 * k);
    const Eigen::Matrix3d R =
        (Eigen::AngleAxisd(0.06 * std::sin(0.7 * k), Eigen::Vector3d::UnitY()) *
         Eigen::AngleAxisd(0.03 * std::cos(0.5 * k), Eigen::Vector3d::UnitX()))
            .toRotationMatrix();
    const Transformationd T_C_G = Transformationd(R, c).inverse();
    scene.T_C_G_true.push_back(T_C_G);
    scene.problem.keyframes.push_back(
        BaKeyframe{static_cast<std::uint64_t>(100 + k), T_C_G, false});
  }
  const double x_max = 4.0 + (o.keyframes - 1) * o.step_m;
  while (static_cast<int>(scene.p_G_true.size()) < o.landmarks) {
    const Eigen::Vector3d p(-4.0 + unit(rng) * (x_max + 4.0), -2.5 + 5.0 * unit(rng),
                            2.0 + 7.0 * unit(rng));
    std::vector<BaObservation> observations;
    bool any_stereo = false;
    for (int k = 0; k < o.keyframes; ++k) {
      const Eigen::Vector3d p_C = scene.T_C_G_true[k] * p;
      if (p_C.z() < 0.5) continue;
      const double u = cam.fx * p_C.x() / p_C.z() + cam.cx;
      const double v = cam.fy * p_C.y() / p_C.z() + cam.cy;
      if (u < 10 || u > scene.width - 10 || v < 10 || v > scene.height - 10) continue;
      if (unit(rng) > o.observe_probability) continue;
      BaObservation obs;
      obs.keyframe = k;
      obs.landmark = static_cast<int>(scene.p_G_true.size());
      const int octave = octave_of(rng);
      const double scale = std::pow(1.2, octave);
      obs.inv_sigma2 = 1.0 / (scale * scale);
      const double sigma = o.pixel_noise * scale;
      obs.u = u + sigma * normal(rng);
      obs.v = v + sigma * normal(rng);
      const double u_right = u - cam.bf / p_C.z();
      const bool stereo = unit(rng) >= o.mono_fraction && u_right >= 0.0;
      obs.u_right = stereo ? u_right + sigma * normal(rng) : -1.0;
      any_stereo = any_stereo || stereo;
      observations.push_back(obs);
    }
    // Every landmark is observed twice or more, once in stereo: well posed in 3D.
    if (observations.size() < 2 || !any_stereo) continue;
    scene.problem.landmarks.push_back(
        BaLandmark{static_cast<std::uint64_t>(5000 + scene.p_G_true.size()), p});
    scene.p_G_true.push_back(p);
    scene.problem.observations.insert(scene.problem.observations.end(), observations.begin(),
                                      observations.end());
  }
  return scene;
}

/// Perturbs the free keyframes' poses (sigma_t metres, sigma_r radians) and every landmark
/// (sigma_p metres per axis) of scene.problem in place.
inline void perturbInitialState(BaScene* scene, double sigma_t, double sigma_r, double sigma_p,
                                std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  for (BaKeyframe& kf : scene->problem.keyframes) {
    if (!kf.fixed) kf.T_C_G = perturbPose(kf.T_C_G, sigma_t, sigma_r, rng);
  }
  for (BaLandmark& lm : scene->problem.landmarks) {
    lm.p_G += sigma_p * Eigen::Vector3d(normal(rng), normal(rng), normal(rng));
  }
}

/// makeBaScene(options) with keyframe 0 fixed (the gauge) and the rest perturbed by
/// perturbInitialState(sigma_t, sigma_r, sigma_p, options.seed + 1).
inline BaScene makeGaugedPerturbedBaScene(const BaSceneOptions& options, double sigma_t,
                                          double sigma_r, double sigma_p) {
  BaScene scene = makeBaScene(options);
  scene.problem.keyframes[0].fixed = true;
  perturbInitialState(&scene, sigma_t, sigma_r, sigma_p, options.seed + 1);
  return scene;
}

struct PoseScene {
  Transformationd T_C_G_true;
  std::vector<PoseObservation> observations;
};

// n observations of random points 2-20 m in front of the camera, 75% stereo, octaves 0-3,
// with pixel noise sigma * 1.2^octave.
inline PoseScene makePoseScene(int n, double pixel_noise, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::normal_distribution<double> normal(0.0, 1.0);
  const StereoCameraModel cam = syntheticCamera();
  PoseScene scene;
  scene.T_C_G_true = perturbPose(Transformationd(), 1.0, 0.5, rng);
  const Transformationd T_G_C = scene.T_C_G_true.inverse();
  for (int i = 0; i < n; ++i) {
    const double z = 2.0 + 18.0 * unit(rng);
    const double u = 10.0 + 732.0 * unit(rng);
    const double v = 10.0 + 460.0 * unit(rng);
    const Eigen::Vector3d p_C((u - cam.cx) * z / cam.fx, (v - cam.cy) * z / cam.fy, z);
    PoseObservation o;
    o.p_G = T_G_C * p_C;
    const double scale = std::pow(1.2, i % 4);
    o.inv_sigma2 = 1.0 / (scale * scale);
    const double sigma = pixel_noise * scale;
    o.u = u + sigma * normal(rng);
    o.v = v + sigma * normal(rng);
    o.u_right = (i % 4 != 3) ? u - cam.bf / z + sigma * normal(rng) : -1.0;
    scene.observations.push_back(o);
  }
  return scene;
}

}  // namespace cblox::test
