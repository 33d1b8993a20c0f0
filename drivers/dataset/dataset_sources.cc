#include "drivers/dataset/dataset_sources.h"

#include <algorithm>
#include <cmath>

namespace cblox {
namespace {

size_t limit(size_t available, size_t max_frames) {
  return max_frames > 0 ? std::min(available, max_frames) : available;
}

}  // namespace

EurocSource::EurocSource(EurocReader reader, size_t max_frames) : reader_(std::move(reader)) {
  count_ = limit(reader_.size(), max_frames);
  info_.name = "euroc:" + reader_.folder();
  info_.rate_hz = reader_.rateHz();
  info_.stereo = reader_.calibration();
  info_.frame_count = count_;
  info_.has_ground_truth = reader_.hasGroundTruth();
  info_.notes = reader_.notes();
  info_.notes.insert(info_.notes.end(), reader_.skipped().begin(), reader_.skipped().end());
}

FrameSource::Status EurocSource::next(CaptureFrame* frame, std::string* error) {
  if (next_ >= count_) return Status::kEnd;
  const size_t i = next_++;
  if (!reader_.read(i, &scratch_, error)) return Status::kError;
  frame->frame_id = static_cast<int64_t>(i);
  frame->timestamp_ns = scratch_.timestamp_ns;
  std::swap(frame->left, scratch_.left);
  std::swap(frame->right, scratch_.right);
  frame->depth = DepthImage();
  frame->color = ColorImage();
  frame->T_G_C = scratch_.T_G_L;
  return Status::kFrame;
}

TumRgbdSource::TumRgbdSource(TumRgbdReader reader, size_t max_frames)
    : reader_(std::move(reader)) {
  count_ = limit(reader_.size(), max_frames);
  info_.name = "tum:" + reader_.folder();
  if (reader_.size() > 1) {
    info_.rate_hz = static_cast<double>(reader_.size() - 1) /
                    (reader_.timestamp(reader_.size() - 1) - reader_.timestamp(0));
  }
  info_.depth_intrinsics = reader_.intrinsics();
  info_.depth_min_m = 0.0;
  info_.depth_max_m = 65535.0 * reader_.depthScale();
  info_.frame_count = count_;
  info_.has_ground_truth = reader_.hasGroundTruth();
  info_.notes = reader_.notes();
  info_.notes.insert(info_.notes.end(), reader_.skipped().begin(), reader_.skipped().end());
}

FrameSource::Status TumRgbdSource::next(CaptureFrame* frame, std::string* error) {
  if (next_ >= count_) return Status::kEnd;
  const size_t i = next_++;
  if (!reader_.read(i, &scratch_, error)) return Status::kError;
  frame->frame_id = static_cast<int64_t>(i);
  frame->timestamp_ns = std::llround(scratch_.timestamp_s * 1e9);
  frame->left = GrayImage();
  frame->right = GrayImage();
  std::swap(frame->depth, scratch_.depth);
  std::swap(frame->color, scratch_.color);
  frame->T_G_C = scratch_.T_G_C;
  return Status::kFrame;
}

SevenScenesSource::SevenScenesSource(SevenScenesReader reader, size_t max_frames)
    : reader_(std::move(reader)) {
  count_ = limit(reader_.size(), max_frames);
  info_.name = "7scenes:" + reader_.folder();
  info_.rate_hz = kRateHz;
  info_.depth_intrinsics = reader_.depthIntrinsics();
  info_.depth_min_m = 0.0;
  info_.depth_max_m = 65.534;
  info_.frame_count = count_;
  info_.has_ground_truth = true;
  info_.notes.push_back("7-Scenes has no time stamps: frame i is stamped i / 30 s");
  info_.notes.push_back("7-Scenes colour is not registered to depth");
}

FrameSource::Status SevenScenesSource::next(CaptureFrame* frame, std::string* error) {
  if (next_ >= count_) return Status::kEnd;
  const size_t i = next_++;
  if (!reader_.read(i, &scratch_, error)) return Status::kError;
  frame->frame_id = static_cast<int64_t>(i);
  frame->timestamp_ns = std::llround(static_cast<double>(i) * 1e9 / kRateHz);
  frame->left = GrayImage();
  frame->right = GrayImage();
  std::swap(frame->depth, scratch_.depth);
  std::swap(frame->color, scratch_.color);
  frame->T_G_C = scratch_.T_G_C;
  return Status::kFrame;
}

}  // namespace cblox
