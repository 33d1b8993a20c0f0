#include "core/submap/submap_creation_policy.h"

#include <cmath>
#include <sstream>
#include <stdexcept>

namespace cblox {

std::string SubmapCreationPolicyConfig::validate() const {
  std::ostringstream error;
  if (max_keyframes_per_subvolume < 1) {
    error << "max_keyframes_per_subvolume must be >= 1, got " << max_keyframes_per_subvolume;
  } else if (!(max_anchor_distance_m >= 0.0) || !std::isfinite(max_anchor_distance_m)) {
    error << "max_anchor_distance_m must be finite and >= 0, got " << max_anchor_distance_m;
  } else if (!(revisit_anchor_distance_m >= 0.0) || !std::isfinite(revisit_anchor_distance_m)) {
    error << "revisit_anchor_distance_m must be finite and >= 0, got " << revisit_anchor_distance_m;
  } else if (revisit_after_frames < 0) {
    error << "revisit_after_frames must be >= 0, got " << revisit_after_frames;
  } else if (revisit_max_frames < 0) {
    error << "revisit_max_frames must be >= 0, got " << revisit_max_frames;
  }
  return error.str();
}

SubmapCreationPolicy::SubmapCreationPolicy(const SubmapCreationPolicyConfig& config)
    : config_(config) {
  const std::string error = config_.validate();
  if (!error.empty()) throw std::invalid_argument("SubmapCreationPolicyConfig: " + error);
}

bool SubmapCreationPolicy::needsNewSubmap(const Submap& active, bool tracking_jump) const {
  return tracking_jump || active.isFinished() ||
         active.numKeyframes() >= static_cast<size_t>(config_.max_keyframes_per_subvolume);
}

SubmapCreationPolicy::FrameAction SubmapCreationPolicy::onFramePose(
    const Submap* active, bool tracking_jump, std::optional<int64_t> frame_time_ns) {
  const bool answered =
      frame_time_ns && active != nullptr && active->creationTimeNs() >= *frame_time_ns;
  if (tracking_jump && !answered) {
    pending_ = Pending::kTrackingJump;
  } else if (active == nullptr || active->isFinished()) {
    if (pending_ != Pending::kTrackingJump) pending_ = Pending::kNoActiveSubmap;
  } else if (pending_ == Pending::kNone && needsNewSubmap(*active, false)) {
    pending_ = Pending::kKeyframeLimit;
  }
  const bool integrate = pending_ == Pending::kNone || pending_ == Pending::kKeyframeLimit;
  return integrate ? FrameAction::kIntegrate : FrameAction::kWaitForAnchor;
}

bool SubmapCreationPolicy::onKeyframe(const Submap* active, bool starts_new_map,
                                      const std::optional<Eigen::Vector3d>& keyframe_position,
                                      std::span<const Eigen::Vector3d> older_anchors) {
  Reason reason = Reason::kNone;
  if (starts_new_map) {
    reason = Reason::kNewMap;
  } else if (pending_ == Pending::kTrackingJump) {
    reason = Reason::kTrackingJump;
  } else if (active == nullptr || active->isFinished() || pending_ == Pending::kNoActiveSubmap) {
    reason = Reason::kNoActiveSubmap;
  } else if (revisit_anchor_ >= 0 && active->anchorKeyframe() == revisit_anchor_) {
    // A revisit subvolume holds frames tracked against its home only: a new keyframe means
    // the tracker now tracks against its own new map, whose poses the home's anchor does not
    // follow (a loop correction moves the new keyframes, not the home).
    reason = Reason::kRevisitEnded;
  } else if (pending_ == Pending::kKeyframeLimit || needsNewSubmap(*active, false)) {
    reason = Reason::kKeyframeLimit;
  } else if (keyframe_position) {
    const Eigen::Vector3d anchor = active->T_G_M().translation();
    const double revisit = config_.revisit_anchor_distance_m;
    if (revisit > 0.0) {
      for (const Eigen::Vector3d& older : older_anchors) {
        if ((*keyframe_position - older).norm() < revisit && (anchor - older).norm() >= revisit) {
          reason = Reason::kRevisit;
          break;
        }
      }
    }
    if (reason == Reason::kNone && config_.max_anchor_distance_m > 0.0 &&
        (*keyframe_position - anchor).norm() > config_.max_anchor_distance_m) {
      reason = Reason::kAnchorDistance;
    }
  }
  if (reason == Reason::kNone) return false;
  pending_ = Pending::kNone;
  revisit_anchor_ = -1;  // the new submap is no revisit submap
  last_reason_ = reason;
  return true;
}

bool SubmapCreationPolicy::onFrameReference(const Submap& active,
                                            const std::optional<ReferenceHome>& home) {
  if (config_.revisit_after_frames <= 0) return false;
  if (!home || atHome(active, *home)) {
    revisit_home_ = -1;
    revisit_votes_ = 0;
    // At home in the revisit submap started last: renewed after revisit_max_frames.
    if (home && revisit_anchor_ == active.anchorKeyframe() && config_.revisit_max_frames > 0 &&
        ++revisit_frames_ >= config_.revisit_max_frames) {
      revisit_frames_ = 0;
      pending_ = Pending::kNone;
      last_reason_ = Reason::kRevisitFrames;
      return true;
    }
    return false;
  }
  if (home->submap != revisit_home_) {
    revisit_home_ = home->submap;
    revisit_votes_ = 0;
  }
  if (++revisit_votes_ < config_.revisit_after_frames) return false;
  return startRevisit(home->anchor, Reason::kRevisitFrames);
}

bool SubmapCreationPolicy::onJumpReference(const Submap* active,
                                           const std::optional<ReferenceHome>& home) {
  if (config_.revisit_after_frames <= 0 || pending_ != Pending::kTrackingJump || !home) {
    return false;
  }
  if (active != nullptr && atHome(*active, *home)) return false;
  return startRevisit(home->anchor, Reason::kRevisitAfterJump);
}

bool SubmapCreationPolicy::atHome(const Submap& active, const ReferenceHome& home) {
  return home.submap == active.id() || home.anchor == active.anchorKeyframe();
}

bool SubmapCreationPolicy::startRevisit(KeyframeId anchor, Reason reason) {
  pending_ = Pending::kNone;
  revisit_home_ = -1;
  revisit_votes_ = 0;
  revisit_anchor_ = anchor;
  revisit_frames_ = 0;
  last_reason_ = reason;
  return true;
}

const char* SubmapCreationPolicy::reasonName(Reason reason) {
  switch (reason) {
    case Reason::kNone:
      return "none";
    case Reason::kNoActiveSubmap:
      return "no active submap";
    case Reason::kNewMap:
      return "new map";
    case Reason::kTrackingJump:
      return "tracking jump";
    case Reason::kKeyframeLimit:
      return "keyframe limit";
    case Reason::kRevisit:
      return "revisit";
    case Reason::kAnchorDistance:
      return "anchor distance";
    case Reason::kRevisitFrames:
      return "tracked in an older subvolume";
    case Reason::kRevisitEnded:
      return "new keyframe after a revisit";
    case Reason::kRevisitAfterJump:
      return "tracked in an older subvolume after a jump";
  }
  return "none";
}

}  // namespace cblox
