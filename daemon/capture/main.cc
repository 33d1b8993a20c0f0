// cblox-capture: plays a capture source (camera through V4L2 or libcamera, simulator, EuRoC,
// TUM RGB-D or 7-Scenes folder) on the LCM channels of the design, or renders it to a folder
// for inspection.
//
//   cblox-capture --list-devices                                 # cameras and their formats
//   cblox-capture --config config/examples/uvc_stereo_pair.yaml  # a real stereo pair
//   cblox-capture --source sim:room --trajectory loop            # publish at 20 Hz
//   cblox-capture --source euroc:../shared/data/euroc-v101-micro --rate max
//   cblox-capture --source sim:town --frames 100 --render-to out/town_frames
//   cblox-capture --source sim:hall --write-scene out/hall.ply
//
// Channels (configurable): CBLOX_STEREO (stereo_pair_t), CBLOX_DEPTH (depth_frame_t),
// CBLOX_GT_POSE (pose_stamped_t, sources with ground truth), CBLOX_HEARTBEAT (1 Hz, from a
// thread of its own; with input_silence_s it reports a source that produces no frames).
// Exit status: 0 done, 1 runtime error, 2 usage or configuration error.

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <csignal>
#include <filesystem>
#include <cstdio>
#include <functional>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include <cblox/heartbeat_t.hpp>
#include <lcm/lcm-cpp.hpp>

#include "core/io/ply_io.h"
#include "daemon/capture/capture_config.h"
#include "daemon/capture/stereo_depth_worker.h"
#include "daemon/common/daemon_options.h"
#include "daemon/common/heartbeat.h"
#include "daemon/common/input_watch.h"
#include "daemon/common/lcm_messages.h"
#include "daemon/common/run_loop.h"
#include "daemon/common/yaml_config.h"
#include "drivers/frame_folder_writer.h"
#include "drivers/libcamera/camera_manager_handle.h"
#include "drivers/v4l2/v4l2_device.h"
#include "drivers/open_frame_source.h"

namespace cblox {
namespace {

using Clock = std::chrono::steady_clock;

struct Args {
  DaemonOptions daemon;
  std::optional<std::string> source, trajectory, rate, noise, depth_encoding, render_to,
      write_scene, calibration;
  bool list_devices = false;
  std::optional<double> device_wait_s;
  std::optional<int> laps, frames;
};

CaptureConfig buildConfig(const Args& args) {
  CaptureConfig config = loadDaemonConfig<CaptureConfig>(args.daemon, loadCaptureConfig);
  if (args.source) config.source = *args.source;
  if (args.trajectory) config.source_config.trajectory = *args.trajectory;
  if (args.laps) {
    if (*args.laps < 1) throw ConfigError("--laps must be >= 1");
    config.source_config.laps = *args.laps;
  }
  if (args.rate) parsePacing(*args.rate, &config);
  if (args.frames) {
    if (*args.frames < 0) throw ConfigError("--frames must be >= 0");
    config.source_config.max_frames = static_cast<size_t>(*args.frames);
  }
  if (args.noise) config.source_config.sim.noise = sensorNoisePreset(*args.noise);
  if (args.calibration) config.source_config.calibration_file = *args.calibration;
  if (args.device_wait_s) {
    if (!(*args.device_wait_s >= 0.0) || !std::isfinite(*args.device_wait_s)) {
      throw ConfigError("--device-wait must be >= 0 seconds");
    }
    config.device_wait_s = *args.device_wait_s;
  }
  if (args.depth_encoding) {
    if (*args.depth_encoding == "u16_mm") {
      config.depth_encoding = DepthEncoding::kUint16Millimetres;
    } else if (*args.depth_encoding == "f32") {
      config.depth_encoding = DepthEncoding::kFloat32Metres;
    } else {
      throw ConfigError("--depth-encoding must be u16_mm or f32, got '" + *args.depth_encoding +
                        "'");
    }
  }
  return config;
}

void printInfo(const SourceInfo& info) {
  std::printf("capture: source %s, %.1f Hz, %s frames\n", info.name.c_str(), info.rate_hz,
              info.frame_count ? std::to_string(*info.frame_count).c_str() : "unknown");
  if (info.stereo) {
    const auto& s = *info.stereo;
    std::printf("capture: stereo %dx%d fx %.2f fy %.2f cx %.2f cy %.2f baseline %.4f m\n",
                s.intrinsics.width, s.intrinsics.height, s.intrinsics.fx, s.intrinsics.fy,
                s.intrinsics.cx, s.intrinsics.cy, s.baseline_m);
  }
  if (info.depth_intrinsics) {
    const auto& K = *info.depth_intrinsics;
    std::printf("capture: depth %dx%d fx %.2f fy %.2f cx %.2f cy %.2f range [%.2f, %.2f] m\n",
                K.width, K.height, K.fx, K.fy, K.cx, K.cy, info.depth_min_m, info.depth_max_m);
  }
  std::printf("capture: ground truth %s\n", info.has_ground_truth ? "yes" : "no");
  for (const std::string& note : info.notes) std::printf("capture: note: %s\n", note.c_str());
  std::fflush(stdout);
}

/// Prints "frames done, rate, ETA" at most every two seconds.
class Progress {
 public:
  Progress(std::optional<size_t> total, bool quiet) : total_(total), quiet_(quiet) {}
  void update(size_t done, bool force = false) {
    const auto now = Clock::now();
    if (quiet_ || (!force && now - last_ < std::chrono::seconds(2))) return;
    last_ = now;
    const double elapsed = std::chrono::duration<double>(now - start_).count();
    const double rate = elapsed > 0 ? done / elapsed : 0.0;
    if (total_ && rate > 0) {
      std::printf("capture: %zu/%zu frames, %.1f frames/s, ETA %.0f s\n", done, *total_, rate,
                  (*total_ - std::min(done, *total_)) / rate);
    } else {
      std::printf("capture: %zu frames, %.1f frames/s\n", done, rate);
    }
    std::fflush(stdout);
  }

 private:
  std::optional<size_t> total_;
  bool quiet_;
  Clock::time_point start_ = Clock::now();
  Clock::time_point last_ = Clock::now();
};

// --list-devices: every V4L2 capture node with the formats, sizes and rates it offers, and
// the cameras libcamera sees.
int listDevices() {
  std::vector<std::string> nodes;
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator("/dev", ec)) {
    const std::string name = entry.path().filename().string();
    if (name.rfind("video", 0) == 0) nodes.push_back(entry.path().string());
  }
  std::sort(nodes.begin(), nodes.end());
  std::printf("V4L2 devices (source v4l2:DEVICE or v4l2-stereo:LEFT,RIGHT):\n");
  if (nodes.empty()) std::printf("  none (no /dev/video*)\n");
  for (const std::string& node : nodes) {
    std::string error;
    const std::unique_ptr<V4l2Device> device = V4l2Device::open(node, &error);
    if (device == nullptr) {
      std::printf("  %s: %s\n", node.c_str(), error.c_str());
      continue;
    }
    std::printf("  %s:\n%s\n", node.c_str(), device->describeFormats().c_str());
  }
  std::string error;
  const std::shared_ptr<libcamera::CameraManager> manager = sharedCameraManager(&error);
  std::printf("libcamera cameras (source libcamera:ID):\n  %s\n",
              manager ? describeLibcameraCameras(*manager).c_str() : error.c_str());
  return 0;
}

int run(const Args& args) {
  if (args.list_devices) return listDevices();
  const CaptureConfig config = buildConfig(args);
  std::string error;
  if (args.write_scene) {
    std::vector<std::string> warnings;
    std::shared_ptr<const Mesh> mesh = loadSimSceneMesh(config.source, &error, &warnings);
    for (const std::string& warning : warnings) {
      std::fprintf(stderr, "cblox-capture: warning: %s\n", warning.c_str());
    }
    if (mesh == nullptr ||
        !writePly(*args.write_scene, *mesh, PlyFormat::kBinaryLittleEndian, &error)) {
      std::fprintf(stderr, "cblox-capture: --write-scene: %s\n", error.c_str());
      return 2;
    }
    std::printf("capture: wrote scene mesh %s (%zu triangles)\n", args.write_scene->c_str(),
                mesh->numTriangles());
    return 0;
  }
  installStopHandlers();
  SystemdNotifier notifier;
  std::vector<std::string> warnings;
  std::unique_ptr<FrameSource> source =
      openFrameSource(config.source, config.source_config, &error, &warnings);
  // A camera that is not there yet (USB enumerating at boot, a cable being plugged) is waited
  // for up to device_wait_s, once a second; then its error stands (exit 2).
  const bool camera = isCameraSpec(config.source);
  if (source == nullptr && camera && config.device_wait_s > 0) {
    std::fprintf(stderr, "cblox-capture: waiting up to %.0f s for the camera: %s\n",
                 config.device_wait_s, error.c_str());
    const auto deadline = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                             std::chrono::duration<double>(config.device_wait_s));
    while (source == nullptr && !g_stop_requested && Clock::now() < deadline) {
      notifier.status("waiting for the camera: " + error);
      notifier.pingWatchdogIfDue();
      std::this_thread::sleep_for(std::chrono::seconds(1));
      warnings.clear();
      source = openFrameSource(config.source, config.source_config, &error, &warnings);
    }
  }
  for (const std::string& warning : warnings) {
    std::fprintf(stderr, "cblox-capture: warning: %s\n", warning.c_str());
  }
  if (source == nullptr) {
    std::fprintf(stderr, "cblox-capture: %s\n", error.c_str());
    return 2;
  }
  if (camera && !args.daemon.quiet) std::printf("capture: camera %s open\n", config.source.c_str());
  const SourceInfo& info = source->info();
  // Dense stereo depth replaces the source's depth camera: the depth images are those of the
  // rectified left camera at the matcher's working resolution.
  std::unique_ptr<StereoDepthEstimator> estimator;
  SourceInfo depth_info = info;
  if (config.stereo_depth) {
    if (!info.stereo) {
      std::fprintf(stderr, "cblox-capture: stereo_depth needs a stereo source; %s has none\n",
                   info.name.c_str());
      return 2;
    }
    if (args.render_to) {
      std::fprintf(stderr, "cblox-capture: stereo_depth publishes on LCM; --render-to writes "
                           "the source's own images (set stereo_depth.matcher: none)\n");
      return 2;
    }
    estimator = StereoDepthEstimator::create(*info.stereo, *config.stereo_depth, &error);
    if (estimator == nullptr) {
      std::fprintf(stderr, "cblox-capture: %s\n", error.c_str());
      return 2;
    }
    depth_info.depth_intrinsics = estimator->depthIntrinsics();
    depth_info.T_C_D = Transformationd::Identity();
    depth_info.depth_min_m = config.stereo_depth->min_depth_m;
    depth_info.depth_max_m = config.stereo_depth->max_depth_m;
    depth_info.notes.push_back(
        std::string("depth from the stereo pair (") +
        stereoMatcherName(config.stereo_depth->matcher) + ", 1/" +
        std::to_string(config.stereo_depth->downscale) + " size, " +
        std::to_string(config.stereo_depth->num_disparities) + " disparities)" +
        (info.depth_intrinsics ? "; the source's depth camera is not published" : ""));
  }
  if (!args.daemon.quiet) printInfo(depth_info);

  std::optional<FrameFolderWriter> writer;
  std::optional<lcm::LCM> lcm;
  if (args.render_to) {
    writer.emplace();
    if (!writer->open(*args.render_to, info, &error)) {
      std::fprintf(stderr, "cblox-capture: %s\n", error.c_str());
      return 1;
    }
  } else {
    lcm.emplace(config.lcm_url);
    if (!lcm->good()) {
      std::fprintf(stderr, "cblox-capture: cannot open LCM (url '%s')\n", config.lcm_url.c_str());
      return 1;
    }
  }

  Progress progress(info.frame_count, args.daemon.quiet);
  notifier.ready("cblox-capture: " + info.name);
  CaptureFrame frame;
  // Counters are read by the heartbeat thread.
  std::atomic<size_t> delivered{0}, errors{0}, publish_failures{0}, gaps{0};
  int64_t last_id = -1;
  std::string last_error;
  std::optional<int64_t> first_stamp_ns;
  const auto start = Clock::now();
  auto last_status = Clock::now() - std::chrono::seconds(2);
  // The input is the frame source: silent when it produced no frame for input_silence_s.
  InputWatch input_watch("cblox-capture", config.input_silence_s);
  const std::string input_name = "source " + config.source;
  input_watch.watch(input_name);
  // The dense-stereo thread publishes depth frames as they are done.
  std::unique_ptr<StereoDepthWorker> depth_worker;
  if (estimator != nullptr) {
    depth_worker = std::make_unique<StereoDepthWorker>(
        std::move(estimator), config.stereo_depth_max_rate_hz, [&](const CaptureFrame& done) {
          if (!config.publish_depth) return;
          const depth_frame_t msg =
              toDepthFrameMsg(done, depth_info, done.timestamp_ns / 1000, config.depth_encoding);
          publish_failures += lcm->publish(config.depth_channel, &msg) != 0;
        });
  }
  auto send_heartbeat = [&](const char* state) {
    if (!lcm) return;
    HeartbeatBuilder hb("cblox-capture", state);
    hb.add("frames_published", static_cast<uint64_t>(delivered.load()))
        .add("source_gaps", static_cast<uint64_t>(gaps.load()))
        .add("source_errors", static_cast<uint64_t>(errors.load()))
        .add("publish_failures", static_cast<uint64_t>(publish_failures.load()));
    if (depth_worker) {
      const StereoDepthWorkerStats d = depth_worker->stats();
      hb.add("stereo_depth_frames", d.computed)
          .add("stereo_depth_superseded", d.superseded)
          .add("stereo_depth_failed", d.failed)
          .addMicroseconds("stereo_depth_mean_us", d.mean_ms)
          .add("stereo_depth_valid_permille", static_cast<int64_t>(1000.0 * d.mean_valid));
    }
    input_watch.addTo(&hb);
    if (const std::string health = source->health(); !health.empty()) {
      hb.setState(hb.state() + "; " + health);
    }
    const heartbeat_t msg = hb.build();
    lcm->publish(config.heartbeat_channel, &msg);  // LCM's publish is thread-safe
  };
  // CBLOX_HEARTBEAT at 1 Hz from a thread of its own, so that it keeps coming (and reports
  // the silence) while the source produces nothing or the pacing waits.
  std::mutex heartbeat_mutex;
  std::condition_variable heartbeat_wake;
  bool heartbeat_done = false;
  std::thread heartbeat_thread;
  if (lcm) {
    heartbeat_thread = std::thread([&] {
      std::unique_lock<std::mutex> lock(heartbeat_mutex);
      while (!heartbeat_done) {
        lock.unlock();
        send_heartbeat("running");
        lock.lock();
        heartbeat_wake.wait_for(lock, std::chrono::seconds(1), [&] { return heartbeat_done; });
      }
    });
  }
  const auto stop_heartbeats = [&] {
    if (!heartbeat_thread.joinable()) return;
    {
      std::lock_guard<std::mutex> lock(heartbeat_mutex);
      heartbeat_done = true;
    }
    heartbeat_wake.notify_all();
    heartbeat_thread.join();
  };
  struct StopOnExit {  // also on an early return or an exception
    std::function<void()> stop;
    ~StopOnExit() { stop(); }
  } stop_on_exit{stop_heartbeats};

  const size_t max_frames = config.source_config.max_frames;  // cameras never end by themselves
  while (!g_stop_requested && !(info.live && max_frames > 0 && delivered >= max_frames)) {
    const FrameSource::Status status = source->next(&frame, &error);
    if (status == FrameSource::Status::kEnd) break;
    if (status == FrameSource::Status::kError) {
      // A camera being reopened reports the same error every second: said once until it
      // changes or frames return.
      ++errors;
      if (error != last_error) std::fprintf(stderr, "cblox-capture: frame skipped: %s\n", error.c_str());
      last_error = error;
      continue;
    }
    last_error.clear();
    input_watch.arrived(input_name);
    if (last_id >= 0 && frame.frame_id > last_id + 1) gaps += frame.frame_id - last_id - 1;
    last_id = frame.frame_id;
    if (!first_stamp_ns) first_stamp_ns = frame.timestamp_ns;

    // Pacing: wait until this frame's time relative to the first one (cameras come at their
    // own pace).
    if (!writer && !info.live && config.pacing != CapturePacing::kMax) {
      const double offset_s = config.pacing == CapturePacing::kSource
                                  ? static_cast<double>(frame.timestamp_ns - *first_stamp_ns) * 1e-9
                                  : static_cast<double>(delivered) / config.fixed_rate_hz;
      std::this_thread::sleep_until(start + std::chrono::duration_cast<Clock::duration>(
                                                std::chrono::duration<double>(offset_s)));
    }

    if (writer) {
      if (!writer->write(frame, &error)) {
        std::fprintf(stderr, "cblox-capture: %s\n", error.c_str());
        return 1;  // no heartbeat thread without LCM
      }
    } else {
      const int64_t utime = frame.timestamp_ns / 1000;
      if (config.publish_stereo && info.stereo && !frame.left.empty()) {
        const stereo_pair_t msg = toStereoPairMsg(frame, info, utime);
        publish_failures += lcm->publish(config.stereo_channel, &msg) != 0;
      }
      if (depth_worker && !frame.left.empty()) depth_worker->offer(frame);
      if (config.publish_depth && !depth_worker && info.depth_intrinsics &&
          !frame.depth.empty()) {
        const depth_frame_t msg = toDepthFrameMsg(frame, info, utime, config.depth_encoding);
        publish_failures += lcm->publish(config.depth_channel, &msg) != 0;
      }
      if (config.publish_ground_truth && frame.T_G_C) {
        const pose_stamped_t msg = toGroundTruthMsg(frame, utime);
        publish_failures += lcm->publish(config.ground_truth_channel, &msg) != 0;
      }
      if (Clock::now() - last_status >= std::chrono::seconds(1)) {
        notifier.status(std::to_string(delivered.load()) + " frames published");
        last_status = Clock::now();
      }
    }
    ++delivered;
    progress.update(delivered);
    notifier.pingWatchdogIfDue();
  }
  if (depth_worker) depth_worker->drain();  // the last pair's depth is published too
  notifier.stopping();
  stop_heartbeats();
  input_watch.stopWatching();  // the last heartbeat says "stopped" / "finished" alone
  send_heartbeat(g_stop_requested ? "stopped" : "finished");
  if (writer && !writer->close(&error)) {
    std::fprintf(stderr, "cblox-capture: %s\n", error.c_str());
    return 1;
  }
  const double elapsed = std::chrono::duration<double>(Clock::now() - start).count();
  std::printf(
      "capture: %s %zu frames in %.1f s (%.1f frames/s); source gaps %zu, skipped %zu, "
      "publish failures %zu%s\n",
      writer ? "wrote" : "published", delivered.load(), elapsed,
      elapsed > 0 ? static_cast<double>(delivered.load()) / elapsed : 0.0, gaps.load(),
      errors.load(), publish_failures.load(), g_stop_requested ? " (stopped by signal)" : "");
  if (writer) std::printf("capture: folder %s\n", args.render_to->c_str());
  if (depth_worker) {
    const StereoDepthWorkerStats d = depth_worker->stats();
    std::printf("capture: stereo depth %llu frames, %.1f ms mean, %.0f %% of pixels valid; "
                "%llu superseded, %llu rate-limited, %llu failed\n",
                static_cast<unsigned long long>(d.computed), d.mean_ms, 100.0 * d.mean_valid,
                static_cast<unsigned long long>(d.superseded),
                static_cast<unsigned long long>(d.rate_limited),
                static_cast<unsigned long long>(d.failed));
  }
  return 0;
}

}  // namespace
}  // namespace cblox

int main(int argc, char** argv) {
  cblox::Args args;
  CLI::App app{
      "cblox-capture: plays a capture source on the LCM channels CBLOX_STEREO, CBLOX_DEPTH,\n"
      "CBLOX_GT_POSE and CBLOX_HEARTBEAT (at the source's rate, a fixed rate or as fast as\n"
      "possible), or renders it to a folder.\n"
      "Exit status: 0 done, 1 runtime error, 2 usage or configuration error.",
      "cblox-capture"};
  cblox::addDaemonOptions(app, &args.daemon, "config/capture.yaml");
  app.add_option("--source", args.source,
                 "sim:room | sim:hall | sim:town | sim:MESH.ply|.obj | euroc:DIR | kitti:DIR |\n"
                 "tum:DIR | 7scenes:DIR | v4l2:/dev/videoN | v4l2-stereo:/dev/videoL,/dev/videoR |\n"
                 "libcamera:CAMERA_ID")
      ->type_name("SPEC");
  app.add_option("--trajectory", args.trajectory,
                 "sim sources: loop | orbit | lawnmower | figure-eight | two-loops | street-turn (town), "
                 "or a "
                 "TUM trajectory file")
      ->type_name("KIND|FILE");
  app.add_option("--laps", args.laps, "laps of the trajectory (>= 1)")->type_name("N");
  app.add_option("--rate", args.rate, "source | max | HZ")->type_name("RATE");
  app.add_option("--frames", args.frames, "frames to play at the most (0: all)")->type_name("N");
  app.add_option("--noise", args.noise, "sensor noise preset: none | realistic")
      ->type_name("PRESET");
  app.add_option("--depth-encoding", args.depth_encoding, "u16_mm | f32")->type_name("ENCODING");
  app.add_option("--calibration", args.calibration,
                 "raw stereo calibration (Kalibr camchain or OpenCV YAML/XML) of a camera\n"
                 "source: frames are rectified at capture")
      ->type_name("FILE");
  app.add_option("--device-wait", args.device_wait_s,
                 "camera sources: wait this long for a camera that is not there yet (s)")
      ->type_name("SECONDS");
  app.add_flag("--list-devices", args.list_devices,
               "list V4L2 devices with their formats, and libcamera cameras, then exit");
  app.add_option("--render-to", args.render_to,
                 "writes images + lists + groundtruth.txt instead of publishing")
      ->type_name("DIR");
  app.add_option("--write-scene", args.write_scene,
                 "writes the simulator's ground-truth mesh (sim sources) and exits")
      ->type_name("FILE.ply");
  if (const std::optional<int> code = cblox::parseCommandLine(app, argc, argv)) return *code;
  return cblox::runProcess("cblox-capture", [&] { return cblox::run(args); });
}
