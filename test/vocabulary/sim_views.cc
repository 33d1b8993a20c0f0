#include "test/vocabulary/sim_views.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "core/features/orb_extractor.h"
#include "core/raycast/triangle_mesh_raycaster.h"

namespace cblox::test {

SimViewRenderer::SimViewRenderer(const std::string& scene_name, uint32_t texture_seed)
    : scene_(makeBuiltinScene(scene_name)) {
  std::string error;
  std::shared_ptr<const TriangleMeshRaycaster> raycaster =
      TriangleMeshRaycaster::create(scene_.mesh, &error);
  if (raycaster == nullptr) throw std::runtime_error(error);
  SimRendererConfig config;
  config.rig.depth_max_m = scene_.depth_max_m;
  config.texture.base_wavelength_m = scene_.texture_wavelength_m;
  config.texture.seed = texture_seed;
  renderer_ = std::make_unique<SimRenderer>(raycaster, config);
}

SimView SimViewRenderer::render(const Transformationd& T_G_C) const {
  const PinholeIntrinsics& in = renderer_->config().rig.stereo;
  GrayImage gray;
  DepthImage depth;
  renderer_->renderView(T_G_C, in, &gray, nullptr, &depth);
  OrbExtractor extractor(OrbExtractorConfig{});
  SimView view{T_G_C, extractor.extract(gray).descriptors, DepthImage(in.width / 4, in.height / 4),
               in};
  view.coarse_camera.fx = in.fx / 4;
  view.coarse_camera.fy = in.fy / 4;
  view.coarse_camera.cx = (in.cx - 2.0) / 4;  // coarse u = (full u - 2) / 4
  view.coarse_camera.cy = (in.cy - 2.0) / 4;
  view.coarse_camera.width = in.width / 4;
  view.coarse_camera.height = in.height / 4;
  for (int v = 0; v < view.coarse_depth.height; ++v) {
    for (int u = 0; u < view.coarse_depth.width; ++u) {
      view.coarse_depth(u, v) = depth(4 * u + 2, 4 * v + 2);
    }
  }
  return view;
}

double viewOverlap(const SimView& a, const SimView& b) {
  const PinholeIntrinsics& ca = a.coarse_camera;
  const PinholeIntrinsics& cb = b.coarse_camera;
  const Transformationd T_B_A = b.T_G_C.inverse() * a.T_G_C;
  int seen = 0, shared = 0;
  for (int v = 0; v < a.coarse_depth.height; ++v) {
    for (int u = 0; u < a.coarse_depth.width; ++u) {
      const double z = a.coarse_depth(u, v);
      if (!(z > 0.0)) continue;
      ++seen;
      const Eigen::Vector3d p_A((u - ca.cx) / ca.fx * z, (v - ca.cy) / ca.fy * z, z);
      const Eigen::Vector3d p_B = T_B_A * p_A;
      if (p_B.z() <= 0.0) continue;
      const int ub = static_cast<int>(std::lround(cb.fx * p_B.x() / p_B.z() + cb.cx));
      const int vb = static_cast<int>(std::lround(cb.fy * p_B.y() / p_B.z() + cb.cy));
      if (!b.coarse_depth.contains(ub, vb)) continue;
      const double zb = b.coarse_depth(ub, vb);
      shared += zb > 0.0 && std::abs(zb - p_B.z()) < 0.05 * p_B.z() + 0.02;
    }
  }
  return seen > 0 ? static_cast<double>(shared) / seen : 0.0;
}

}  // namespace cblox::test
