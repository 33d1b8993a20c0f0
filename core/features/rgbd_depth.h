#pragma once

#include <vector>

#include "core/features/keypoint.h"
#include "core/features/stereo_depth.h"
#include "core/geometry/image.h"

namespace cblox {

/// RGB-D mode (ORB-SLAM2's Frame::ComputeStereoFromRGBD): depth of each keypoint from a depth
/// image registered to the keypoints' camera (same intrinsics and pose, pixel for pixel), and
/// the column it would have in the right image of a virtual stereo rig, so that RGB-D frames
/// feed the same stereo reprojection error as stereo frames:
///   z = depth(round(u), round(v)) if that pixel is inside the image, finite and > 0, else
///   none; right_u = u - bf / z.
/// `bf` = fx * baseline of the virtual rig (pixels x metres), ORB-SLAM2's "Camera.bf" setting
/// (e.g. 40 for the TUM Kinect: fx ~ 517 px times a ~ 0.08 m IR projector baseline). It only
/// sets how strongly the virtual right coordinate constrains depth in the optimisation; the
/// tracker's close/far split (ORB-SLAM2's ThDepth, in multiples of the baseline bf / fx) is
/// not applied here. Keypoints without depth get right_u = depth = -1; right_index is -1.
/// Throws std::invalid_argument for an empty depth image, a data size that does not match its
/// width * height, or bf not finite and > 0. Thread-safe (pure).
StereoDepth depthFromRgbd(const std::vector<Keypoint>& keypoints, const DepthImage& depth,
                          double bf);

}  // namespace cblox
