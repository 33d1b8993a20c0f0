#pragma once

#include <cstddef>
#include <string>

#include "drivers/dataset/euroc_reader.h"
#include "drivers/dataset/kitti_odometry_reader.h"
#include "drivers/dataset/seven_scenes_reader.h"
#include "drivers/dataset/tum_rgbd_reader.h"
#include "drivers/frame_source.h"

namespace cblox {

/// A recorded dataset played in order: frames 0 .. count - 1 read by index. A frame that
/// cannot be read is reported (kError) and skipped; the next call goes on with the next one.
/// Thread-safety: not thread-safe.
class IndexedFrameSource : public FrameSource {
 public:
  const SourceInfo& info() const override { return info_; }
  Status next(CaptureFrame* frame, std::string* error) final;

 protected:
  /// Plays min(available, max_frames) frames (all when max_frames is 0); sets
  /// info.frame_count accordingly.
  IndexedFrameSource(SourceInfo info, size_t available, size_t max_frames);

  /// Reads frame i (< the frame count) into *frame, or returns false with a message.
  virtual bool readFrame(size_t i, CaptureFrame* frame, std::string* error) = 0;

 private:
  SourceInfo info_;
  size_t count_ = 0;
  size_t next_ = 0;
};

/// EuRoC/ASL stereo folder: rectified left/right grey images, the dataset's nanosecond time
/// stamps, ground truth of the rectified left camera when the folder has it.
class EurocSource : public IndexedFrameSource {
 public:
  /// max_frames = 0 plays all frames.
  EurocSource(EurocReader reader, size_t max_frames);

 private:
  bool readFrame(size_t i, CaptureFrame* frame, std::string* error) override;

  EurocReader reader_;
  EurocStereoFrame scratch_;
};

/// KITTI odometry grey stereo sequence: the rectified image_0 / image_1 pairs, times.txt's
/// time stamps, camera 0's ground truth when the sequence has a pose file.
class KittiSource : public IndexedFrameSource {
 public:
  /// max_frames = 0 plays all frames.
  KittiSource(KittiOdometryReader reader, size_t max_frames);

 private:
  bool readFrame(size_t i, CaptureFrame* frame, std::string* error) override;

  KittiOdometryReader reader_;
  KittiStereoFrame scratch_;
};

/// TUM RGB-D folder: depth (metres) with the associated colour image, the dataset's time
/// stamps, interpolated ground truth.
class TumRgbdSource : public IndexedFrameSource {
 public:
  TumRgbdSource(TumRgbdReader reader, size_t max_frames);

 private:
  bool readFrame(size_t i, CaptureFrame* frame, std::string* error) override;

  TumRgbdReader reader_;
  TumRgbdFrame scratch_;
};

/// 7-Scenes frame folder. The layout has no time stamps: frame i is stamped i / 30 s (the
/// Kinect's rate) and this is said in info().notes, as is the fact that the colour camera
/// is not registered to the depth camera.
class SevenScenesSource : public IndexedFrameSource {
 public:
  static constexpr double kRateHz = 30.0;

  SevenScenesSource(SevenScenesReader reader, size_t max_frames);

 private:
  bool readFrame(size_t i, CaptureFrame* frame, std::string* error) override;

  SevenScenesReader reader_;
  SevenScenesFrame scratch_;
};

}  // namespace cblox
