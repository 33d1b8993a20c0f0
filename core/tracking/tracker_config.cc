#include "core/tracking/tracker_config.h"

#include <cmath>
#include <sstream>

namespace cblox {

std::string TrackerConfig::validate() const {
  std::ostringstream error;
  auto positive = [&](const char* name, double value) {
    if (error.tellp() == 0 && !(std::isfinite(value) && value > 0.0)) {
      error << name << " must be finite and > 0, got " << value;
    }
  };
  positive("min_features_to_initialize", min_features_to_initialize);
  positive("min_new_landmarks_per_keyframe", min_new_landmarks_per_keyframe);
  positive("max_frames_between_keyframes", max_frames_between_keyframes);
  positive("reference_ratio", reference_ratio);
  positive("last_frame_search_radius", last_frame_search_radius);
  positive("local_map_search_radius", local_map_search_radius);
  positive("relocalized_search_radius", relocalized_search_radius);
  positive("min_motion_model_matches", min_motion_model_matches);
  positive("min_reference_matches", min_reference_matches);
  positive("min_pose_inliers", min_pose_inliers);
  positive("min_local_map_inliers", min_local_map_inliers);
  positive("max_local_keyframes", max_local_keyframes);
  positive("max_relocalization_candidates", max_relocalization_candidates);
  positive("min_relocalization_matches", min_relocalization_matches);
  positive("pnp_iterations", pnp_iterations);
  positive("pnp_reprojection_error_px", pnp_reprojection_error_px);
  if (error.tellp() == 0 && close_points_min_frames < 0) {
    error << "close_points_min_frames must be >= 0, got " << close_points_min_frames;
  }
  if (error.tellp() == 0 && !(close_points_turn_deg >= 0.0 && close_points_turn_deg <= 180.0)) {
    error << "close_points_turn_deg must be in [0, 180], got " << close_points_turn_deg;
  }
  if (error.tellp() == 0 && close_points_gap_min_inliers < 0) {
    error << "close_points_gap_min_inliers must be >= 0, got " << close_points_gap_min_inliers;
  }
  if (error.tellp() == 0 && min_frames_between_keyframes < 0) {
    error << "min_frames_between_keyframes must be >= 0, got " << min_frames_between_keyframes;
  }
  if (error.tellp() == 0 && min_frames_between_keyframes > max_frames_between_keyframes) {
    error << "min_frames_between_keyframes (" << min_frames_between_keyframes
          << ") must be <= max_frames_between_keyframes (" << max_frames_between_keyframes << ")";
  }
  if (error.tellp() == 0 && reference_ratio > 1.0) {
    error << "reference_ratio must be <= 1, got " << reference_ratio;
  }
  return error.str();
}

}  // namespace cblox
