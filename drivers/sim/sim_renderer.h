#pragma once

#include <memory>
#include <string>
#include <vector>

#include "core/geometry/image.h"
#include "core/geometry/pinhole_camera.h"
#include "core/geometry/se3.h"
#include "core/raycast/triangle_mesh_raycaster.h"
#include "drivers/sim/procedural_texture.h"
#include "drivers/sim/sim_rig.h"

namespace cblox {

/// Exact (noise-free) images of one rig pose.
struct SimImages {
  GrayImage left;    ///< rectified left camera, 8-bit grey
  GrayImage right;   ///< rectified right camera, 8-bit grey
  ColorImage color;  ///< RGB seen by the depth camera (registered to `depth`)
  DepthImage depth;  ///< depth camera z in metres; 0 where nothing is seen within range
};

struct SimRendererConfig {
  SimRigConfig rig;
  ProceduralTextureConfig texture;
  SimLightingConfig lighting;
  /// Threads used per render (rows are interleaved in bands of 8).
  int num_threads = 2;

  std::string validate() const;
};

/// Renders a triangle-mesh scene for the simulated rig by ray tracing (Embree): one primary
/// ray per pixel through its centre, Lambertian shading of the vertex colour modulated by the
/// procedural texture. Depth is the exact z of the first hit (float precision); pixels that
/// see nothing, or beyond the depth range, are 0.
/// Thread-safety: immutable after construction; render() is thread-safe (each call uses its
/// own threads and writes only to its output).
class SimRenderer {
 public:
  /// Throws std::invalid_argument with the config's validation message, or if scene is null.
  SimRenderer(std::shared_ptr<const TriangleMeshRaycaster> scene, const SimRendererConfig& config);

  /// Renders all four images at the rig pose T_G_L (left camera in the world). *images is
  /// resized as needed (reusing its memory). Thread-safe.
  void render(const Transformationd& T_G_L, SimImages* images) const;

  /// Renders one pinhole view at T_G_C: any of gray, color, depth may be null. Thread-safe.
  void renderView(const Transformationd& T_G_C, const PinholeIntrinsics& intrinsics,
                  GrayImage* gray, ColorImage* color, DepthImage* depth) const;

  const SimRendererConfig& config() const { return config_; }
  const TriangleMeshRaycaster& scene() const { return *scene_; }

 private:
  /// Renders rows band by band: bands of 8 rows, band b on thread b % num_threads.
  void renderRows(const Transformationd& T_G_C, const PinholeIntrinsics& intrinsics,
                  GrayImage* gray, ColorImage* color, DepthImage* depth, int thread_id,
                  int num_threads) const;

  /// Vertex colour of the hit point (barycentric interpolation unless the triangle is flat).
  Eigen::Vector3f albedo(const RaycastHit& hit) const;
  /// Light falling on a surface with this (unit, camera-facing) normal.
  float light(const Eigen::Vector3f& normal) const;

  struct TriangleColor {
    Eigen::Vector3f c0{200.0f, 200.0f, 200.0f}, c1{200.0f, 200.0f, 200.0f},
        c2{200.0f, 200.0f, 200.0f};
    bool flat = true;
  };

  std::shared_ptr<const TriangleMeshRaycaster> scene_;
  SimRendererConfig config_;
  ProceduralTexture texture_;
  Eigen::Vector3f towards_light_G_;
  float ambient_ = 0.0f, diffuse_ = 0.0f;
  std::vector<TriangleColor> triangle_colors_;
};

}  // namespace cblox
