#pragma once

// The tracker's own command-line options over its config (cblox-tracker, and cblox-replay,
// which runs the same tracker): --mode, --initial-pose-from-gt, --calibration, --vocabulary.

#include <optional>
#include <string>

#include <CLI/CLI.hpp>

#include "daemon/tracker/tracker_config.h"

namespace cblox {

struct TrackerOptions {
  std::optional<std::string> mode;         ///< --mode stereo|rgbd
  bool initial_pose_from_gt = false;       ///< --initial-pose-from-gt
  std::optional<std::string> calibration;  ///< --calibration FILE
  std::optional<std::string> vocabulary;   ///< --vocabulary FILE|none
};

/// Adds the four options to `app`, writing into *options (which must outlive the parse).
inline void addTrackerOptions(CLI::App& app, TrackerOptions* options) {
  app.add_option("--mode", options->mode, "stereo | rgbd")->type_name("MODE");
  app.add_flag("--initial-pose-from-gt", options->initial_pose_from_gt,
               "the first keyframe takes its pose from CBLOX_GT_POSE (initial_pose:\n"
               "ground_truth): G = the simulator's frame");
  app.add_option("--calibration", options->calibration,
                 "Kalibr/EuRoC-style camera file instead of the messages'")
      ->type_name("FILE");
  app.add_option("--vocabulary", options->vocabulary, "vocabulary file, or none")
      ->type_name("FILE|none");
}

/// Applies the options given over `config`, then finishTrackerConfig() (loads the
/// calibration file, validates). Throws ConfigError naming the option or key.
inline void applyTrackerOptions(const TrackerOptions& options, TrackerProcessConfig* config) {
  if (options.mode) config->tracker.mode = parseTrackerMode(*options.mode);
  if (options.initial_pose_from_gt) config->tracker.initial_pose = InitialPose::kGroundTruth;
  if (options.calibration) {
    config->calibration_source = CalibrationSource::kFile;
    config->calibration_file = *options.calibration;
  }
  if (options.vocabulary) config->vocabulary = *options.vocabulary;
  finishTrackerConfig(config);
}

}  // namespace cblox
