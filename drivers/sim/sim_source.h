#pragma once

#include <memory>
#include <string>
#include <utility>

#include "core/io/tum_trajectory.h"
#include "core/raycast/triangle_mesh_raycaster.h"
#include "drivers/frame_source.h"
#include "drivers/sim/sensor_model.h"
#include "drivers/sim/sim_renderer.h"

namespace cblox {

struct SimSourceConfig {
  SimRendererConfig renderer;
  SensorNoiseConfig noise;
  /// Camera frame rate; frames are rendered at t0 + k / rate_hz along the trajectory.
  double rate_hz = 20.0;
  /// Stop after this many frames (0 = play the whole trajectory).
  size_t max_frames = 0;

  std::string validate() const;
};

/// The simulated rig as a capture source: renders the scene along a trajectory of the left
/// camera (poses interpolated at the frame times), applies the sensor model, and delivers
/// stereo, depth, colour and the exact pose T_G_C of the left camera.
/// Thread-safety: not thread-safe (next() advances a cursor); renders use the renderer's
/// threads internally.
class SimSource : public FrameSource {
 public:
  /// Throws std::invalid_argument for an invalid config, a null scene or a trajectory with
  /// fewer than one pose.
  SimSource(std::string name, std::shared_ptr<const TriangleMeshRaycaster> scene,
            StampedTrajectory trajectory_G_L, const SimSourceConfig& config);

  const SourceInfo& info() const override { return info_; }
  Status next(CaptureFrame* frame, std::string* error) override;

  /// Appends a remark to info().notes, e.g. a warning about the scene file the mesh came from
  /// (openFrameSource() adds the loader's warnings). Never fails. Not thread-safe; call before
  /// handing the source to its reader.
  void addNote(std::string note) { info_.notes.push_back(std::move(note)); }

  /// Frames this source plays (before drops).
  size_t frameCount() const { return frame_count_; }
  const StampedTrajectory& trajectory() const { return trajectory_; }
  const SimRenderer& renderer() const { return renderer_; }

 private:
  Transformationd poseAt(double t) const;

  StampedTrajectory trajectory_;
  SimSourceConfig config_;
  SimRenderer renderer_;
  SensorModel sensor_;
  SourceInfo info_;
  size_t frame_count_ = 0;
  size_t next_ = 0;
  SimImages scratch_;
};

}  // namespace cblox
