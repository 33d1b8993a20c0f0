#include "drivers/dataset/dataset_sources.h"

#include <algorithm>
#include <cmath>
#include <optional>
#include <vector>

namespace cblox {
namespace {

std::vector<std::string> joined(std::vector<std::string> a, const std::vector<std::string>& b) {
  a.insert(a.end(), b.begin(), b.end());
  return a;
}

SourceInfo eurocInfo(const EurocReader& reader) {
  SourceInfo info;
  info.name = "euroc:" + reader.folder();
  info.rate_hz = reader.rateHz();
  info.stereo = reader.calibration();
  info.has_ground_truth = reader.hasGroundTruth();
  info.notes = joined(reader.notes(), reader.skipped());
  return info;
}

SourceInfo kittiInfo(const KittiOdometryReader& reader) {
  SourceInfo info;
  info.name = "kitti:" + reader.folder();
  info.rate_hz = reader.rateHz();
  info.stereo = reader.calibration();
  info.has_ground_truth = reader.hasGroundTruth();
  info.notes = reader.notes();
  return info;
}

SourceInfo tumInfo(const TumRgbdReader& reader) {
  SourceInfo info;
  info.name = "tum:" + reader.folder();
  if (reader.size() > 1) {
    info.rate_hz = static_cast<double>(reader.size() - 1) /
                   (reader.timestamp(reader.size() - 1) - reader.timestamp(0));
  }
  info.depth_intrinsics = reader.intrinsics();
  info.depth_max_m = 65535.0 * reader.depthScale();
  info.has_ground_truth = reader.hasGroundTruth();
  info.notes = joined(reader.notes(), reader.skipped());
  return info;
}

SourceInfo sevenScenesInfo(const SevenScenesReader& reader) {
  SourceInfo info;
  info.name = "7scenes:" + reader.folder();
  info.rate_hz = SevenScenesSource::kRateHz;
  info.depth_intrinsics = reader.depthIntrinsics();
  info.depth_max_m = 65.534;
  info.has_ground_truth = true;
  info.notes = {"7-Scenes has no time stamps: frame i is stamped i / 30 s",
                "7-Scenes colour is not registered to depth"};
  return info;
}

/// A depth-camera frame (no stereo pair): takes the images out of the reader's scratch frame.
void fillDepthFrame(size_t i, int64_t timestamp_ns, DepthImage* depth, ColorImage* color,
                    const std::optional<Transformationd>& T_G_C, CaptureFrame* frame) {
  frame->frame_id = static_cast<int64_t>(i);
  frame->timestamp_ns = timestamp_ns;
  frame->left = GrayImage();
  frame->right = GrayImage();
  std::swap(frame->depth, *depth);
  std::swap(frame->color, *color);
  frame->T_G_C = T_G_C;
}

/// A stereo frame (no depth): takes the images out of the reader's scratch frame.
void fillStereoFrame(size_t i, int64_t timestamp_ns, GrayImage* left, GrayImage* right,
                     const std::optional<Transformationd>& T_G_L, CaptureFrame* frame) {
  frame->frame_id = static_cast<int64_t>(i);
  frame->timestamp_ns = timestamp_ns;
  std::swap(frame->left, *left);
  std::swap(frame->right, *right);
  frame->depth = DepthImage();
  frame->color = ColorImage();
  frame->T_G_C = T_G_L;
}

}  // namespace

IndexedFrameSource::IndexedFrameSource(SourceInfo info, size_t available, size_t max_frames)
    : info_(std::move(info)),
      count_(max_frames > 0 ? std::min(available, max_frames) : available) {
  info_.frame_count = count_;
}

FrameSource::Status IndexedFrameSource::next(CaptureFrame* frame, std::string* error) {
  if (next_ >= count_) return Status::kEnd;
  const size_t i = next_++;
  return readFrame(i, frame, error) ? Status::kFrame : Status::kError;
}

EurocSource::EurocSource(EurocReader reader, size_t max_frames)
    : IndexedFrameSource(eurocInfo(reader), reader.size(), max_frames),
      reader_(std::move(reader)) {}

bool EurocSource::readFrame(size_t i, CaptureFrame* frame, std::string* error) {
  if (!reader_.read(i, &scratch_, error)) return false;
  fillStereoFrame(i, scratch_.timestamp_ns, &scratch_.left, &scratch_.right, scratch_.T_G_L,
                  frame);
  return true;
}

KittiSource::KittiSource(KittiOdometryReader reader, size_t max_frames)
    : IndexedFrameSource(kittiInfo(reader), reader.size(), max_frames),
      reader_(std::move(reader)) {}

bool KittiSource::readFrame(size_t i, CaptureFrame* frame, std::string* error) {
  if (!reader_.read(i, &scratch_, error)) return false;
  fillStereoFrame(i, scratch_.timestamp_ns, &scratch_.left, &scratch_.right, scratch_.T_G_L,
                  frame);
  return true;
}

TumRgbdSource::TumRgbdSource(TumRgbdReader reader, size_t max_frames)
    : IndexedFrameSource(tumInfo(reader), reader.size(), max_frames),
      reader_(std::move(reader)) {}

bool TumRgbdSource::readFrame(size_t i, CaptureFrame* frame, std::string* error) {
  if (!reader_.read(i, &scratch_, error)) return false;
  fillDepthFrame(i, std::llround(scratch_.timestamp_s * 1e9), &scratch_.depth, &scratch_.color,
                 scratch_.T_G_C, frame);
  return true;
}

SevenScenesSource::SevenScenesSource(SevenScenesReader reader, size_t max_frames)
    : IndexedFrameSource(sevenScenesInfo(reader), reader.size(), max_frames),
      reader_(std::move(reader)) {}

bool SevenScenesSource::readFrame(size_t i, CaptureFrame* frame, std::string* error) {
  if (!reader_.read(i, &scratch_, error)) return false;
  fillDepthFrame(i, std::llround(static_cast<double>(i) * 1e9 / kRateHz), &scratch_.depth,
                 &scratch_.color, scratch_.T_G_C, frame);
  return true;
}

}  // namespace cblox
