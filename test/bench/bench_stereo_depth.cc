// Dense stereo depth benchmark: time per pair at 752x480 and accuracy of each matcher
// (drivers/stereo_depth) against the simulator's exact depth, and on the Middlebury 2006
// "Aloe" pair that Debian's opencv-doc ships with its true disparity.
//
//   cblox-bench-stereo-depth [--scenes room,hall] [--frames N] [--threads T] [--json FILE]
//                            [--middlebury DIR]
//
// Simulator: N pairs (default 20) spread over each scene's loop, realistic image noise and
// exposure drift, no depth noise (the reference is exact). Each pair is matched 3 times and
// the fastest kept (the host is shared). Accuracy: median and p90 |z_est - z| overall and by
// metre of z, completeness (share of pixels with an exact depth that got an estimate) and
// outliers (|error| > 10 % of z). OpenCV runs with T threads (default 1: one core).

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "core/common/quantile.h"
#include "daemon/common/cli.h"
#include "drivers/open_frame_source.h"
#include "drivers/stereo_depth/depth_accuracy.h"
#include "drivers/stereo_depth/stereo_depth.h"

namespace cblox {
namespace {

using Clock = std::chrono::steady_clock;

struct Variant {
  std::string name;
  StereoDepthConfig config;
};

std::vector<Variant> variants() {
  std::vector<Variant> out;
  for (const StereoMatcherType matcher : {StereoMatcherType::kSgbm, StereoMatcherType::kSgbm3Way,
                                          StereoMatcherType::kBlockMatching}) {
    for (const int downscale : {1, 2}) {
      StereoDepthConfig c;
      c.matcher = matcher;
      c.downscale = downscale;
      c.num_disparities = downscale == 1 ? 128 : 64;  // same nearest depth: 0.39 m
      c.block_size = matcher == StereoMatcherType::kBlockMatching ? (downscale == 1 ? 15 : 9) : 5;
      c.min_depth_m = 0.4;
      c.max_depth_m = 10.0;
      out.push_back({std::string(stereoMatcherName(matcher)) + " 1/" + std::to_string(downscale),
                     c});
    }
  }
  return out;
}

double fastestMs(StereoDepthEstimator* estimator, const CaptureFrame& frame, DepthImage* depth) {
  double best = 1e9;
  for (int r = 0; r < 3; ++r) {
    const auto start = Clock::now();
    estimator->compute(frame.left, frame.right, depth);
    best = std::min(best,
                    std::chrono::duration<double, std::milli>(Clock::now() - start).count());
  }
  return best;
}

double median(std::vector<double> v) { return quantile(&v, 0.5); }

nlohmann::json benchScene(const std::string& scene, int frames,
                          const std::vector<Variant>& all) {
  SourceConfig options;
  options.sim.noise.image_noise_sigma = 2.0;
  options.sim.noise.exposure_amplitude = 0.15;
  options.sim.noise.exposure_period_s = 7.0;
  std::string error;
  auto probe = openFrameSource("sim:" + scene, options, &error);
  if (probe == nullptr) throw std::runtime_error(error);
  const size_t total = probe->info().frame_count.value_or(static_cast<size_t>(frames));
  const size_t step = std::max<size_t>(1, total / static_cast<size_t>(frames));
  options.max_frames = step * static_cast<size_t>(frames);
  auto source = openFrameSource("sim:" + scene, options, &error);
  if (source == nullptr) throw std::runtime_error(error);
  std::vector<CaptureFrame> pairs;
  CaptureFrame frame;
  for (size_t i = 0; source->next(&frame, &error) == FrameSource::Status::kFrame; ++i) {
    if (i % step == 0) pairs.push_back(frame);
  }
  std::printf("\n%s: %zu pairs (every %zu of the loop's frames), 752x480, baseline %.3f m\n",
              scene.c_str(), pairs.size(), step, source->info().stereo->baseline_m);
  std::printf("  %-14s %8s %9s %9s %8s %8s %7s\n", "matcher", "ms", "med |e|", "p90 |e|",
              "med rel", "outl.", "compl.");
  nlohmann::json rows = nlohmann::json::array();
  for (const Variant& v : all) {
    auto estimator = StereoDepthEstimator::create(*source->info().stereo, v.config, &error);
    if (estimator == nullptr) throw std::runtime_error(error);
    std::vector<double> ms, med, p90, rel, outliers, completeness;
    std::vector<std::vector<double>> by_z_med(12), by_z_p90(12);
    for (const CaptureFrame& pair : pairs) {
      DepthImage depth;
      ms.push_back(fastestMs(estimator.get(), pair, &depth));
      const DepthAccuracy a = compareToExactDepth(depth, v.config.downscale, pair.depth);
      med.push_back(a.median_abs_m);
      p90.push_back(a.p90_abs_m);
      rel.push_back(a.median_rel);
      outliers.push_back(a.outlier_fraction);
      completeness.push_back(a.completeness);
      for (const DepthErrorBin& bin : a.bins) {
        const size_t k = static_cast<size_t>(bin.z_min_m);
        if (k < by_z_med.size() && bin.samples >= 100) {
          by_z_med[k].push_back(bin.median_abs_m);
          by_z_p90[k].push_back(bin.p90_abs_m);
        }
      }
    }
    std::printf("  %-14s %8.1f %6.1f mm %6.1f mm %7.2f%% %7.1f%% %6.0f%%\n",
                v.name.c_str(), median(ms), 1000 * median(med),
                1000 * median(p90), 100 * median(rel), 100 * median(outliers),
                100 * median(completeness));
    nlohmann::json by_z = nlohmann::json::array();
    std::ostringstream line;
    for (size_t k = 0; k < by_z_med.size(); ++k) {
      if (by_z_med[k].empty()) continue;
      by_z.push_back({{"z_m", k + 0.5},
                      {"median_abs_mm", 1000 * median(by_z_med[k])},
                      {"p90_abs_mm", 1000 * median(by_z_p90[k])}});
      line << " " << k << "-" << k + 1 << " m: " << static_cast<int>(1000 * median(by_z_med[k]))
           << "/" << static_cast<int>(1000 * median(by_z_p90[k]));
    }
    std::printf("  %-14s by z, median/p90 mm:%s\n", "", line.str().c_str());
    rows.push_back({{"matcher", v.name},
                    {"ms_median", median(ms)},
                    {"median_abs_mm", 1000 * median(med)},
                    {"p90_abs_mm", 1000 * median(p90)},
                    {"median_rel", median(rel)},
                    {"outlier_fraction", median(outliers)},
                    {"completeness", median(completeness)},
                    {"by_z", by_z}});
  }
  return {{"scene", scene}, {"pairs", pairs.size()}, {"rows", rows}};
}

// Middlebury 2006 Aloe, full size: disparity of the left view against aloeGT.png (8-bit, the
// disparity in pixels; 0 = unknown).
nlohmann::json benchMiddlebury(const std::string& dir) {
  const cv::Mat left = cv::imread(dir + "/aloeL.jpg", cv::IMREAD_GRAYSCALE);
  const cv::Mat right = cv::imread(dir + "/aloeR.jpg", cv::IMREAD_GRAYSCALE);
  const cv::Mat gt = cv::imread(dir + "/aloeGT.png", cv::IMREAD_UNCHANGED);
  if (left.empty() || right.empty() || gt.empty()) {
    std::printf("\nmiddlebury: aloeL.jpg/aloeR.jpg/aloeGT.png not in %s (apt-get install "
                "opencv-doc); skipped\n",
                dir.c_str());
    return nullptr;
  }
  std::printf("\nmiddlebury aloe %dx%d: bad pixels (|d - d_true| > 1 / 2 px) over pixels with a "
              "true disparity, non-occluded or not\n",
              left.cols, left.rows);
  std::printf("  %-14s %8s %8s %8s %8s %9s\n", "matcher", "ms", "valid", "bad1", "bad2",
              "med |e|px");
  nlohmann::json rows = nlohmann::json::array();
  for (const StereoMatcherType matcher : {StereoMatcherType::kSgbm, StereoMatcherType::kSgbm3Way,
                                          StereoMatcherType::kBlockMatching}) {
    // The same matchers as StereoDepthEstimator at full size, on raw disparities.
    StereoDepthConfig c;
    c.matcher = matcher;
    c.downscale = 1;
    c.num_disparities = 256;
    c.block_size = matcher == StereoMatcherType::kBlockMatching ? 15 : 5;
    RectifiedStereoCalibration calibration;
    calibration.intrinsics = {1000.0, 1000.0, left.cols / 2.0, left.rows / 2.0, left.cols,
                              left.rows};
    calibration.baseline_m = 1.0;  // z = 1000 / d: depth back to disparity exactly
    c.min_depth_m = 1000.0 / 256.0;
    c.max_depth_m = 1e6;
    std::string error;
    auto estimator = StereoDepthEstimator::create(calibration, c, &error);
    if (estimator == nullptr) throw std::runtime_error(error);
    GrayImage l(left.cols, left.rows), r(right.cols, right.rows);
    std::copy(left.datastart, left.dataend, l.data.begin());
    std::copy(right.datastart, right.dataend, r.data.begin());
    CaptureFrame frame;
    frame.left = l;
    frame.right = r;
    DepthImage depth;
    const double ms = fastestMs(estimator.get(), frame, &depth);
    size_t known = 0, valid = 0, bad1 = 0, bad2 = 0;
    std::vector<double> errors;
    for (int v = 0; v < gt.rows; ++v) {
      for (int u = 0; u < gt.cols; ++u) {
        const int d_true = gt.at<uint8_t>(v, u);
        if (d_true == 0) continue;
        ++known;
        const float z = depth(u, v);
        if (!(z > 0)) continue;
        ++valid;
        const double e = std::abs(1000.0 / z - d_true);
        errors.push_back(e);
        bad1 += e > 1.0;
        bad2 += e > 2.0;
      }
    }
    const double k = static_cast<double>(std::max<size_t>(valid, 1));
    std::printf("  %-14s %8.1f %7.0f%% %7.1f%% %7.1f%% %9.2f\n", stereoMatcherName(matcher), ms,
                100.0 * valid / std::max<size_t>(known, 1), 100.0 * bad1 / k, 100.0 * bad2 / k,
                median(errors));
    rows.push_back({{"matcher", stereoMatcherName(matcher)},
                    {"ms", ms},
                    {"valid", static_cast<double>(valid) / std::max<size_t>(known, 1)},
                    {"bad1", bad1 / k},
                    {"bad2", bad2 / k},
                    {"median_abs_px", median(errors)}});
  }
  return {{"pair", "aloe"}, {"width", left.cols}, {"height", left.rows}, {"rows", rows}};
}

int run(int argc, char** argv) {
  std::string scenes = "room,hall", json_path;
  std::string middlebury = "/usr/share/doc/opencv-doc/examples/data";
  int frames = 20, threads = 1;
  CLI::App app{"cblox-bench-stereo-depth: dense stereo depth, ms per 752x480 pair and accuracy\n"
               "against the simulator's exact depth and Middlebury's true disparity.",
               "cblox-bench-stereo-depth"};
  app.add_option("--scenes", scenes, "comma-separated built-in scenes")->capture_default_str();
  app.add_option("--frames", frames, "pairs per scene")->capture_default_str();
  app.add_option("--threads", threads, "OpenCV threads")->capture_default_str();
  app.add_option("--middlebury", middlebury, "folder of aloeL.jpg, aloeR.jpg, aloeGT.png")
      ->capture_default_str();
  app.add_option("--json", json_path, "write the figures as JSON");
  if (const std::optional<int> exit = parseCommandLine(app, argc, argv)) return *exit;
  if (frames < 1 || threads < 1) {
    std::fprintf(stderr, "cblox-bench-stereo-depth: --frames and --threads must be >= 1\n");
    return 2;
  }
  cv::setNumThreads(threads);
  std::printf("cblox-bench-stereo-depth: OpenCV %s, %d thread(s)\n", CV_VERSION, threads);
  nlohmann::json out{{"threads", threads}, {"scenes", nlohmann::json::array()}};
  std::stringstream list(scenes);
  std::string scene;
  const std::vector<Variant> all = variants();
  while (std::getline(list, scene, ',')) out["scenes"].push_back(benchScene(scene, frames, all));
  out["middlebury"] = benchMiddlebury(middlebury);
  if (!json_path.empty()) {
    std::ofstream(json_path) << out.dump(2) << "\n";
    std::printf("wrote %s\n", json_path.c_str());
  }
  return 0;
}

}  // namespace
}  // namespace cblox

int main(int argc, char** argv) {
  try {
    return cblox::run(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "cblox-bench-stereo-depth: %s\n", e.what());
    return 1;
  }
}
