#include "test/bench/open3d_peer.h"

#include <chrono>
#include <cstring>

#include <omp.h>
#include <open3d/Open3D.h>

namespace cblox::bench {

Open3dResult runOpen3dScalableTsdf(const BenchSequence& sequence, float voxel_size,
                                   float truncation, float max_depth, int num_threads) {
  omp_set_num_threads(num_threads);
  using open3d::geometry::Image;
  using open3d::geometry::RGBDImage;
  const PinholeIntrinsics& K = sequence.intrinsics;
  const open3d::camera::PinholeCameraIntrinsic intrinsic(K.width, K.height, K.fx, K.fy, K.cx, K.cy);
  open3d::pipelines::integration::ScalableTSDFVolume volume(
      voxel_size, truncation, open3d::pipelines::integration::TSDFVolumeColorType::RGB8);
  Open3dResult result;
  for (const BenchFrame& frame : sequence.frames) {
    Image depth, color;
    depth.Prepare(K.width, K.height, 1, 4);
    std::memcpy(depth.data_.data(), frame.depth.data.data(),
                frame.depth.data.size() * sizeof(float));
    color.Prepare(K.width, K.height, 3, 1);
    std::memcpy(color.data_.data(), frame.color.data.data(), frame.color.data.size() * 3);
    // Depth is already float metres: depth_scale 1.
    const auto rgbd = RGBDImage::CreateFromColorAndDepth(color, depth, 1.0, max_depth, false);
    const Eigen::Matrix4d extrinsic = frame.T_G_C.inverse().matrix();
    const auto start = std::chrono::steady_clock::now();
    volume.Integrate(*rgbd, intrinsic, extrinsic);
    result.frame_ms.push_back(
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
            .count());
  }
  result.mesh_positions = volume.ExtractTriangleMesh()->vertices_;
  result.mesh_vertices = result.mesh_positions.size();
  return result;
}

}  // namespace cblox::bench
