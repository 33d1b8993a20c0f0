#pragma once

#include <cstddef>
#include <string>

#include "drivers/dataset/euroc_reader.h"
#include "drivers/dataset/seven_scenes_reader.h"
#include "drivers/dataset/tum_rgbd_reader.h"
#include "drivers/frame_source.h"

namespace cblox {

/// EuRoC/ASL stereo folder as a FrameSource: rectified left/right grey images, the
/// dataset's nanosecond time stamps, ground truth of the rectified left camera when the
/// folder has it. A frame whose image cannot be read is reported (kError) and skipped.
/// Thread-safety: not thread-safe.
class EurocSource : public FrameSource {
 public:
  /// max_frames = 0 plays all frames.
  EurocSource(EurocReader reader, size_t max_frames);
  const SourceInfo& info() const override { return info_; }
  Status next(CaptureFrame* frame, std::string* error) override;

 private:
  EurocReader reader_;
  SourceInfo info_;
  size_t count_ = 0;
  size_t next_ = 0;
  EurocStereoFrame scratch_;
};

/// TUM RGB-D folder as a FrameSource: depth (metres) with the associated colour image, the
/// dataset's time stamps, interpolated ground truth. Thread-safety: not thread-safe.
class TumRgbdSource : public FrameSource {
 public:
  TumRgbdSource(TumRgbdReader reader, size_t max_frames);
  const SourceInfo& info() const override { return info_; }
  Status next(CaptureFrame* frame, std::string* error) override;

 private:
  TumRgbdReader reader_;
  SourceInfo info_;
  size_t count_ = 0;
  size_t next_ = 0;
  TumRgbdFrame scratch_;
};

/// 7-Scenes frame folder as a FrameSource. The layout has no time stamps: frame i is stamped
/// i / 30 s (the Kinect's rate) and this is said in info().notes, as is the fact that the
/// colour camera is not registered to the depth camera. Thread-safety: not thread-safe.
class SevenScenesSource : public FrameSource {
 public:
  static constexpr double kRateHz = 30.0;

  SevenScenesSource(SevenScenesReader reader, size_t max_frames);
  const SourceInfo& info() const override { return info_; }
  Status next(CaptureFrame* frame, std::string* error) override;

 private:
  SevenScenesReader reader_;
  SourceInfo info_;
  size_t count_ = 0;
  size_t next_ = 0;
  SevenScenesFrame scratch_;
};

}  // namespace cblox
