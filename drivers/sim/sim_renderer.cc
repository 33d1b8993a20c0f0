#include "drivers/sim/sim_renderer.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

#include "core/common/thread_team.h"

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
  // The data size is checked too: a moved-from image keeps its width and height but no
  // pixels.
  if (image->width != width || image->height != height ||
      image->data.size() != static_cast<size_t>(width) * static_cast<size_t>(height)) {
    *image = Image<T>(width, height);
  }
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
  ambient_ = static_cast<float>(config.lighting.ambient);
  diffuse_ = static_cast<float>(config.lighting.diffuse);
  // Vertex colours per triangle as floats; most primitives are one colour (flat).
  const Mesh& mesh = scene_->mesh();
  triangle_colors_.resize(mesh.triangles.size());
  for (size_t i = 0; i < mesh.triangles.size(); ++i) {
    TriangleColor& c = triangle_colors_[i];
    if (!mesh.hasColors()) continue;  // default grey
    const Eigen::Vector3i& t = mesh.triangles[i];
    auto to_float = [](const Color& k) { return Eigen::Vector3f(k.r, k.g, k.b); };
    c.c0 = to_float(mesh.colors[t[0]]);
    c.c1 = to_float(mesh.colors[t[1]]);
    c.c2 = to_float(mesh.colors[t[2]]);
    c.flat = mesh.colors[t[0]] == mesh.colors[t[1]] && mesh.colors[t[0]] == mesh.colors[t[2]];
  }
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
  renderView(T_G_L * T_L_R, rig.rightIntrinsics(), &images->right, nullptr, nullptr);
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

// Cloned for x86-64-v3 (AVX2, FMA) with a baseline fallback, chosen at load time. Not under
// ThreadSanitizer: the clone's resolver runs before TSan's runtime is up and crashes at load.
// Not under clang (the fuzz build): it refuses to clone a function already used above.
#if defined(__x86_64__) && !defined(__SANITIZE_THREAD__) && !defined(__clang__)
#define CBLOX_RENDER_CLONES [[gnu::target_clones("arch=x86-64-v3", "default")]]
#else
#define CBLOX_RENDER_CLONES
#endif
CBLOX_RENDER_CLONES void SimRenderer::renderRows(
    const Transformationd& T_G_C, const PinholeIntrinsics& intrinsics, GrayImage* gray,
    ColorImage* color, DepthImage* depth, int thread_id, int num_threads) const {
  const int width = intrinsics.width, height = intrinsics.height;
  const Eigen::Matrix3f R_G_C = T_G_C.rotationMatrix().cast<float>();
  const Eigen::Vector3f origin_G = T_G_C.translation().cast<float>();
  const float fx = static_cast<float>(intrinsics.fx), fy = static_cast<float>(intrinsics.fy);
  const float cx = static_cast<float>(intrinsics.cx), cy = static_cast<float>(intrinsics.cy);
  const float depth_min = static_cast<float>(config_.rig.depth_min_m);
  const float depth_max = static_cast<float>(config_.rig.depth_max_m);
  const uint8_t background = static_cast<uint8_t>(config_.lighting.background_gray);
  const bool shade = gray != nullptr || color != nullptr;

  std::vector<RaycastHit> hits(static_cast<size_t>(width) * kRowBand);
  // Shading in two passes per row: geometry of every hit, then the texture of all of them
  // in one SIMD batch.
  std::vector<ProceduralTexture::TextureSample> samples(static_cast<size_t>(width));
  std::vector<Eigen::Vector3f> lit_albedo(static_cast<size_t>(width));
  std::vector<int> sample_column(static_cast<size_t>(width));
  std::vector<float> texture(static_cast<size_t>(width));
  // Normalised x of every column, and 1 / fx: no division per pixel.
  std::vector<float> column_x(static_cast<size_t>(width));
  for (int u = 0; u < width; ++u) column_x[static_cast<size_t>(u)] = (static_cast<float>(u) - cx) / fx;
  const float inverse_fx = 1.0f / fx;
  for (int band = thread_id; band * kRowBand < height; band += num_threads) {
    const int row_begin = band * kRowBand;
    const int row_end = std::min(height, row_begin + kRowBand);
    scene_->intersectPinholeRows(R_G_C, origin_G, intrinsics, row_begin, row_end, hits);
    for (int v = row_begin; v < row_end; ++v) {
      const RaycastHit* row_hits = hits.data() + static_cast<size_t>(v - row_begin) * width;
      const float y = (static_cast<float>(v) - cy) / fy;
      size_t num_samples = 0;
      for (int u = 0; u < width; ++u) {
        const RaycastHit& hit = row_hits[u];
        if (!hit.hit()) {
          if (gray != nullptr) (*gray)(u, v) = background;
          if (color != nullptr) (*color)(u, v) = Color{background, background, background};
          if (depth != nullptr) (*depth)(u, v) = 0.0f;
          continue;
        }
        if (depth != nullptr) {
          (*depth)(u, v) = (hit.t >= depth_min && hit.t <= depth_max) ? hit.t : 0.0f;
        }
        if (!shade) continue;
        const Eigen::Vector3f direction =
            R_G_C * Eigen::Vector3f(column_x[static_cast<size_t>(u)], y, 1.0f);
        const float ray_length = direction.norm();
        Eigen::Vector3f normal = hit.normal;
        float cos_incidence = -normal.dot(direction) * (1.0f / ray_length);
        if (cos_incidence < 0.0f) {  // back face: shade the side the camera sees
          normal = -normal;
          cos_incidence = -cos_incidence;
        }
        // One pixel's size on the surface: distance / focal length, stretched by obliquity
        // along one axis only; the texture filter uses the geometric mean of the two axes
        // (like anisotropic filtering, it keeps detail on surfaces seen at grazing angles).
        const float footprint =
            hit.t * ray_length * inverse_fx / std::sqrt(std::max(cos_incidence, 0.05f));
        samples[num_samples] = {origin_G + hit.t * direction, normal, footprint};
        lit_albedo[num_samples] = albedo(hit) * light(normal);
        sample_column[num_samples] = u;
        ++num_samples;
      }
      texture_.brightness(std::span(samples.data(), num_samples), texture);
      for (size_t k = 0; k < num_samples; ++k) {
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

Eigen::Vector3f SimRenderer::albedo(const RaycastHit& hit) const {
  const TriangleColor& c = triangle_colors_[hit.triangle];
  if (c.flat) return c.c0;
  const float w0 = 1.0f - hit.u - hit.v;
  return w0 * c.c0 + hit.u * c.c1 + hit.v * c.c2;
}

float SimRenderer::light(const Eigen::Vector3f& normal) const {
  return ambient_ + diffuse_ * (0.5f + 0.5f * normal.dot(towards_light_G_));
}

}  // namespace cblox
