#include "drivers/sim/sim_renderer.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

#include "core/integrator/thread_team.h"

namespace cblox {
namespace {

constexpr int kRowBand = 8;

uint8_t toByte(float value) {
  return static_cast<uint8_t>(std::clamp(value + 0.5f, 0.0f, 255.0f));
}

}  // namespace

namespace {

template <typename T>
void resizeImage(Image<T>* image, int width, int height) {
  if (image == nullptr) return;
  if (image->width != width || image->height != height) *image = Image<T>(width, height);
}

}  // namespace

std::string SimRendererConfig::validate() const {
  if (std::string problem = rig.validate(); !problem.empty()) return "rig: " + problem;
  if (std::string problem = texture.validate(); !problem.empty()) return "texture: " + problem;
  if (std::string problem = lighting.validate(); !problem.empty()) return "lighting: " + problem;
  if (num_threads < 1) return "num_threads must be >= 1, got " + std::to_string(num_threads);
  return {};
}

static const SimRendererConfig& checked(const SimRendererConfig& config) {
  if (const std::string problem = config.validate(); !problem.empty()) {
    throw std::invalid_argument("SimRendererConfig: " + problem);
  }
  return config;
}

SimRenderer::SimRenderer(std::shared_ptr<const TriangleMeshRaycaster> scene,
                         const SimRendererConfig& config)
    : scene_(std::move(scene)), config_(checked(config)), texture_(config_.texture) {
  if (scene_ == nullptr) throw std::invalid_argument("SimRenderer: scene is null");
  towards_light_G_ = config.lighting.towards_light_G.normalized().cast<float>();
}

void SimRenderer::render(const Transformationd& T_G_L, SimImages* images) const {
  const SimRigConfig& rig = config_.rig;
  const Transformationd T_L_R(Eigen::Quaterniond::Identity(),
                              Eigen::Vector3d(rig.baseline_m, 0.0, 0.0));
  if (rig.depthIsLeftCamera()) {
    renderView(T_G_L, rig.stereo, &images->left, &images->color, &images->depth);
  } else {
    renderView(T_G_L, rig.stereo, &images->left, nullptr, nullptr);
    renderView(T_G_L * rig.T_L_D, rig.depthIntrinsics(), nullptr, &images->color,
               &images->depth);
  }
  renderView(T_G_L * T_L_R, rig.stereo, &images->right, nullptr, nullptr);
}

void SimRenderer::renderView(const Transformationd& T_G_C, const PinholeIntrinsics& intrinsics,
                             GrayImage* gray, ColorImage* color, DepthImage* depth) const {
  resizeImage(gray, intrinsics.width, intrinsics.height);
  resizeImage(color, intrinsics.width, intrinsics.height);
  resizeImage(depth, intrinsics.width, intrinsics.height);
  const int num_threads =
      std::min(config_.num_threads, (intrinsics.height + kRowBand - 1) / kRowBand);
  runThreadTeam(num_threads, [&](int thread_id) {
    renderRows(T_G_C, intrinsics, gray, color, depth, thread_id, num_threads);
  });
}

// Cloned for x86-64-v3 (AVX2, FMA) with a baseline fallback, chosen at load time.
[[gnu::target_clones("arch=x86-64-v3", "default")]] void SimRenderer::renderRows(
    const Transformationd& T_G_C, const PinholeIntrinsics& intrinsics, GrayImage* gray,
    ColorImage* color, DepthImage* depth, int thread_id, int num_threads) const {
  const int width = intrinsics.width, height = intrinsics.height;
  const Eigen::Matrix3f R_G_C = T_G_C.rotationMatrix().cast<float>();
  const Eigen::Vector3f origin_G = T_G_C.translation().cast<float>();
  const float fx = static_cast<float>(intrinsics.fx), fy = static_cast<float>(intrinsics.fy);
  const float cx = static_cast<float>(intrinsics.cx), cy = static_cast<float>(intrinsics.cy);
  const float depth_min = static_cast<float>(config_.rig.depth_min_m);
  const float depth_max = static_cast<float>(config_.rig.depth_max_m);
  const float ambient = static_cast<float>(config_.lighting.ambient);
  const float diffuse = static_cast<float>(config_.lighting.diffuse);
  const uint8_t background = static_cast<uint8_t>(config_.lighting.background_gray);
  const Mesh& mesh = scene_->mesh();
  const bool has_colors = mesh.hasColors();
  std::vector<Ray> rays(static_cast<size_t>(width));
  std::vector<RaycastHit> hits(static_cast<size_t>(width));
  // Shading in two passes per row: geometry of every hit, then the texture of all of them
  // in one SIMD batch.
  std::vector<ProceduralTexture::TextureSample> samples;
  std::vector<Eigen::Vector3f> lit_albedo;
  std::vector<int> sample_column;
  std::vector<float> texture(static_cast<size_t>(width));
  samples.reserve(static_cast<size_t>(width));
  lit_albedo.reserve(static_cast<size_t>(width));
  sample_column.reserve(static_cast<size_t>(width));
  for (int band = thread_id; band * kRowBand < height; band += num_threads) {
    const int row_end = std::min(height, (band + 1) * kRowBand);
    for (int v = band * kRowBand; v < row_end; ++v) {
      const float y = (static_cast<float>(v) - cy) / fy;
      for (int u = 0; u < width; ++u) {
        Ray& ray = rays[static_cast<size_t>(u)];
        ray.origin = origin_G;
        // Scaled to z = 1 in the camera frame: the hit's t is its depth.
        ray.direction = R_G_C * Eigen::Vector3f((static_cast<float>(u) - cx) / fx, y, 1.0f);
        ray.t_near = 0.0f;
        ray.t_far = std::numeric_limits<float>::infinity();
      }
      scene_->intersect(rays, hits);
      samples.clear();
      lit_albedo.clear();
      sample_column.clear();
      for (int u = 0; u < width; ++u) {
        const RaycastHit& hit = hits[static_cast<size_t>(u)];
        if (!hit.hit()) {
          if (gray != nullptr) (*gray)(u, v) = background;
          if (color != nullptr) (*color)(u, v) = Color{background, background, background};
          if (depth != nullptr) (*depth)(u, v) = 0.0f;
          continue;
        }
        const Ray& ray = rays[static_cast<size_t>(u)];
        if (depth != nullptr) {
          (*depth)(u, v) = (hit.t >= depth_min && hit.t <= depth_max) ? hit.t : 0.0f;
        }
        if (gray == nullptr && color == nullptr) continue;
        const float ray_length = ray.direction.norm();
        Eigen::Vector3f normal = hit.normal;
        float cos_incidence = -normal.dot(ray.direction) / ray_length;
        if (cos_incidence < 0.0f) {  // back face: shade the side the camera sees
          normal = -normal;
          cos_incidence = -cos_incidence;
        }
        // One pixel's size on the surface: distance / focal length, stretched by obliquity.
        const float footprint = hit.t * ray_length / fx / std::max(cos_incidence, 0.2f);
        samples.push_back({ray.origin + hit.t * ray.direction, normal, footprint});
        const float light = ambient + diffuse * (0.5f + 0.5f * normal.dot(towards_light_G_));
        Eigen::Vector3f albedo(200.0f, 200.0f, 200.0f);
        if (has_colors) {
          const Eigen::Vector3i& tri = mesh.triangles[hit.triangle];
          const float w0 = 1.0f - hit.u - hit.v;
          const Color& c0 = mesh.colors[tri[0]];
          const Color& c1 = mesh.colors[tri[1]];
          const Color& c2 = mesh.colors[tri[2]];
          albedo = w0 * Eigen::Vector3f(c0.r, c0.g, c0.b) +
                   hit.u * Eigen::Vector3f(c1.r, c1.g, c1.b) +
                   hit.v * Eigen::Vector3f(c2.r, c2.g, c2.b);
        }
        lit_albedo.push_back(albedo * light);
        sample_column.push_back(u);
      }
      texture_.brightness(samples, texture);
      for (size_t k = 0; k < samples.size(); ++k) {
        const int u = sample_column[k];
        const Eigen::Vector3f rgb = lit_albedo[k] * texture[k];
        if (gray != nullptr) {
          (*gray)(u, v) = toByte(0.299f * rgb.x() + 0.587f * rgb.y() + 0.114f * rgb.z());
        }
        if (color != nullptr) {
          (*color)(u, v) = Color{toByte(rgb.x()), toByte(rgb.y()), toByte(rgb.z())};
        }
      }
    }
  }
}

}  // namespace cblox
