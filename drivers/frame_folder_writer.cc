#include "drivers/frame_folder_writer.h"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

namespace cblox {
namespace {

namespace fs = std::filesystem;

void setError(std::string* error, std::string message) {
  if (error != nullptr) *error = std::move(message);
}

std::string stamp(int64_t timestamp_ns) {
  char buffer[64];
  std::snprintf(buffer, sizeof(buffer), "%.6f", static_cast<double>(timestamp_ns) * 1e-9);
  return buffer;
}

bool writeText(const std::string& path, const std::string& text, std::string* error) {
  std::ofstream out(path);
  out << text;
  out.close();
  if (!out) {
    setError(error, path + ": cannot write");
    return false;
  }
  return true;
}

bool writePng(const std::string& path, const cv::Mat& image, std::string* error) {
  try {
    if (cv::imwrite(path, image)) return true;
  } catch (const cv::Exception& e) {
    setError(error, path + ": " + e.what());
    return false;
  }
  setError(error, path + ": cannot write PNG");
  return false;
}

}  // namespace

bool FrameFolderWriter::open(const std::string& folder, const SourceInfo& info,
                             std::string* error, double depth_units_per_metre) {
  if (!(depth_units_per_metre > 0.0)) {
    setError(error, "depth_units_per_metre must be > 0");
    return false;
  }
  folder_ = folder;
  info_ = info;
  units_per_metre_ = depth_units_per_metre;
  std::error_code ec;
  for (const char* sub : {"", "rgb", "depth", "left", "right"}) {
    const bool needed = std::string(sub).empty() ||
                        ((std::string(sub) == "left" || std::string(sub) == "right")
                             ? info.stereo.has_value()
                             : info.depth_intrinsics.has_value());
    if (!needed) continue;
    fs::create_directories(fs::path(folder) / sub, ec);
    if (ec) {
      setError(error, (fs::path(folder) / sub).string() + ": cannot create: " + ec.message());
      return false;
    }
  }
  const std::string header = "# timestamp filename (written by cblox-capture from " + info.name + ")\n";
  rgb_list_ = depth_list_ = left_list_ = right_list_ = header;
  if (info.depth_intrinsics.has_value()) {
    const PinholeIntrinsics& K = *info.depth_intrinsics;
    char text[256];
    std::snprintf(text, sizeof(text), "%.10g 0 %.10g\n0 %.10g %.10g\n0 0 1\n", K.fx, K.cx, K.fy,
                  K.cy);
    if (!writeText(folder + "/camera-intrinsics.txt", text, error)) return false;
  }
  if (info.stereo.has_value()) {
    const RectifiedStereoCalibration& s = *info.stereo;
    char text[512];
    std::snprintf(text, sizeof(text),
                  "# Rectified stereo pair: both cameras share these intrinsics; the right camera\n"
                  "# is at (+baseline_m, 0, 0) in the left camera frame.\n"
                  "width: %d\nheight: %d\nfx: %.10g\nfy: %.10g\ncx: %.10g\ncy: %.10g\n"
                  "baseline_m: %.10g\n",
                  s.intrinsics.width, s.intrinsics.height, s.intrinsics.fx, s.intrinsics.fy,
                  s.intrinsics.cx, s.intrinsics.cy, s.baseline_m);
    if (!writeText(folder + "/stereo.yaml", text, error)) return false;
  }
  return true;
}

bool FrameFolderWriter::write(const CaptureFrame& frame, std::string* error) {
  const std::string t = stamp(frame.timestamp_ns);
  if (!frame.left.empty() && !frame.right.empty()) {
    const cv::Mat left(frame.left.height, frame.left.width, CV_8UC1,
                       const_cast<uint8_t*>(frame.left.data.data()));
    const cv::Mat right(frame.right.height, frame.right.width, CV_8UC1,
                        const_cast<uint8_t*>(frame.right.data.data()));
    if (!writePng(folder_ + "/left/" + t + ".png", left, error)) return false;
    if (!writePng(folder_ + "/right/" + t + ".png", right, error)) return false;
    left_list_ += t + " left/" + t + ".png\n";
    right_list_ += t + " right/" + t + ".png\n";
  }
  if (!frame.depth.empty()) {
    cv::Mat depth(frame.depth.height, frame.depth.width, CV_16UC1);
    for (int v = 0; v < frame.depth.height; ++v) {
      for (int u = 0; u < frame.depth.width; ++u) {
        const double d = frame.depth(u, v);
        uint16_t value = 0;
        if (std::isfinite(d) && d > 0.0) {
          const double units = std::round(d * units_per_metre_);
          if (units > 65535.0) {
            ++out_of_range_;
          } else {
            value = static_cast<uint16_t>(units);
          }
        }
        depth.at<uint16_t>(v, u) = value;
      }
    }
    if (!writePng(folder_ + "/depth/" + t + ".png", depth, error)) return false;
    depth_list_ += t + " depth/" + t + ".png\n";
  }
  if (!frame.color.empty()) {
    cv::Mat bgr(frame.color.height, frame.color.width, CV_8UC3);
    for (int v = 0; v < frame.color.height; ++v) {
      for (int u = 0; u < frame.color.width; ++u) {
        const Color& c = frame.color(u, v);
        bgr.at<cv::Vec3b>(v, u) = cv::Vec3b(c.b, c.g, c.r);
      }
    }
    if (!writePng(folder_ + "/rgb/" + t + ".png", bgr, error)) return false;
    rgb_list_ += t + " rgb/" + t + ".png\n";
  }
  if (frame.T_G_C.has_value()) {
    ground_truth_.push_back({static_cast<double>(frame.timestamp_ns) * 1e-9, *frame.T_G_C});
  }
  ++frames_;
  return true;
}

bool FrameFolderWriter::close(std::string* error) {
  if (info_.depth_intrinsics.has_value()) {
    if (!writeText(folder_ + "/depth.txt", depth_list_, error)) return false;
    if (!writeText(folder_ + "/rgb.txt", rgb_list_, error)) return false;
  }
  if (info_.stereo.has_value()) {
    if (!writeText(folder_ + "/left.txt", left_list_, error)) return false;
    if (!writeText(folder_ + "/right.txt", right_list_, error)) return false;
  }
  if (!ground_truth_.empty() &&
      !writeTumTrajectory(folder_ + "/groundtruth.txt", ground_truth_, error)) {
    return false;
  }
  std::string text = "source: " + info_.name + "\nframes: " + std::to_string(frames_) + "\n";
  if (out_of_range_ > 0) {
    text += "depth pixels beyond the 16-bit range written as 0: " +
            std::to_string(out_of_range_) + "\n";
  }
  for (const std::string& note : info_.notes) text += "note: " + note + "\n";
  return writeText(folder_ + "/source.txt", text, error);
}

}  // namespace cblox
