#include "daemon/capture/capture_config.h"

#include <gtest/gtest.h>

#include "daemon/common/yaml_config.h"

namespace cblox {
namespace {

TEST(CaptureConfigTest, ShippedYamlMatchesTheCodeDefaults) {
  const CaptureConfig shipped =
      loadCaptureConfig(loadYamlFile(std::string(CBLOX_CONFIG_DIR) + "/capture.yaml"));
  const CaptureConfig defaults;
  EXPECT_EQ(shipped.source, defaults.source);
  EXPECT_EQ(shipped.source_config.trajectory, defaults.source_config.trajectory);
  EXPECT_EQ(shipped.source_config.laps, defaults.source_config.laps);
  EXPECT_EQ(shipped.pacing, defaults.pacing);
  EXPECT_EQ(shipped.source_config.max_frames, defaults.source_config.max_frames);
  EXPECT_EQ(shipped.lcm_url, defaults.lcm_url);
  EXPECT_EQ(shipped.device_wait_s, defaults.device_wait_s);
  EXPECT_EQ(shipped.source_config.calibration_file, defaults.source_config.calibration_file);
  EXPECT_EQ(shipped.depth_encoding, defaults.depth_encoding);
  EXPECT_EQ(shipped.stereo_channel, defaults.stereo_channel);
  EXPECT_EQ(shipped.depth_channel, defaults.depth_channel);
  EXPECT_EQ(shipped.ground_truth_channel, defaults.ground_truth_channel);
  EXPECT_EQ(shipped.heartbeat_channel, defaults.heartbeat_channel);
  const SimSourceConfig& a = shipped.source_config.sim;
  const SimSourceConfig& b = defaults.source_config.sim;
  EXPECT_EQ(a.rate_hz, b.rate_hz);
  EXPECT_EQ(a.renderer.num_threads, b.renderer.num_threads);
  EXPECT_EQ(a.renderer.rig.stereo.width, b.renderer.rig.stereo.width);
  EXPECT_EQ(a.renderer.rig.stereo.height, b.renderer.rig.stereo.height);
  EXPECT_EQ(a.renderer.rig.stereo.fx, b.renderer.rig.stereo.fx);
  EXPECT_EQ(a.renderer.rig.stereo.cx, b.renderer.rig.stereo.cx);
  EXPECT_EQ(a.renderer.rig.stereo.cy, b.renderer.rig.stereo.cy);
  EXPECT_EQ(a.renderer.rig.baseline_m, b.renderer.rig.baseline_m);
  EXPECT_EQ(a.renderer.rig.right_cx_error_px, b.renderer.rig.right_cx_error_px);
  EXPECT_EQ(a.renderer.rig.depth_min_m, b.renderer.rig.depth_min_m);
  EXPECT_EQ(a.renderer.rig.depth_max_m, b.renderer.rig.depth_max_m);
  EXPECT_FALSE(a.noise.any());
  // stereo_depth: matcher none, and the other keys as StereoDepthConfig's defaults.
  EXPECT_FALSE(shipped.stereo_depth.has_value());
  EXPECT_EQ(shipped.stereo_depth_max_rate_hz, defaults.stereo_depth_max_rate_hz);
  YAML::Node file = loadYamlFile(std::string(CBLOX_CONFIG_DIR) + "/capture.yaml");
  file["stereo_depth"]["matcher"] = "sgbm";
  const StereoDepthConfig on = *loadCaptureConfig(file).stereo_depth;
  const StereoDepthConfig d;
  EXPECT_EQ(on.downscale, d.downscale);
  EXPECT_EQ(on.num_disparities, d.num_disparities);
  EXPECT_EQ(on.block_size, d.block_size);
  EXPECT_EQ(on.uniqueness_ratio, d.uniqueness_ratio);
  EXPECT_EQ(on.left_right_max_diff, d.left_right_max_diff);
  EXPECT_EQ(on.speckle_window, d.speckle_window);
  EXPECT_EQ(on.speckle_range, d.speckle_range);
  EXPECT_EQ(on.texture_threshold, d.texture_threshold);
  EXPECT_EQ(on.min_depth_m, d.min_depth_m);
  EXPECT_EQ(on.max_depth_m, d.max_depth_m);
}

// The example configs of the README load, and say what they claim.
TEST(CaptureConfigTest, ExampleConfigsLoad) {
  const std::string dir = std::string(CBLOX_CONFIG_DIR) + "/examples/";
  const auto load = [&](const char* name) { return loadCaptureConfig(loadYamlFile(dir + name)); };
  const CaptureConfig sim = load("sim_stereo_depth.yaml");
  ASSERT_TRUE(sim.stereo_depth.has_value());
  EXPECT_EQ(sim.stereo_depth->matcher, StereoMatcherType::kSgbm);
  EXPECT_EQ(sim.stereo_depth->min_depth_m, 0.4);
  const CaptureConfig car = load("sim_kitti_rig.yaml");
  EXPECT_EQ(car.source, "sim:town");
  EXPECT_EQ(car.source_config.sim.rate_hz, 10.0);
  EXPECT_EQ(car.source_config.sim.renderer.rig.stereo.width, 1241);
  EXPECT_EQ(car.source_config.sim.renderer.rig.stereo.height, 376);
  EXPECT_EQ(car.source_config.sim.renderer.rig.stereo.fx, 718.856);
  EXPECT_EQ(car.source_config.sim.renderer.rig.baseline_m, 0.5372);
  EXPECT_GT(car.source_config.sim.noise.image_noise_sigma, 0.0);  // the realistic preset
  const CaptureConfig kitti = load("kitti_stereo_depth.yaml");
  EXPECT_EQ(kitti.source, "kitti:../shared/data/kitti-odometry-51");
  ASSERT_TRUE(kitti.stereo_depth.has_value());
  EXPECT_EQ(kitti.stereo_depth->num_disparities, 96);
  EXPECT_EQ(kitti.stereo_depth->max_depth_m, 30.0);
  const CaptureConfig pair = load("uvc_stereo_pair.yaml");
  EXPECT_EQ(pair.source, "v4l2-stereo:/dev/video0,/dev/video2");
  EXPECT_EQ(pair.source_config.v4l2.pixel_format, "GREY");
  EXPECT_EQ(pair.source_config.v4l2.exposure, 100);
  EXPECT_FALSE(pair.source_config.calibration_file.empty());
  const CaptureConfig sbs = load("side_by_side_usb.yaml");
  EXPECT_EQ(sbs.source_config.v4l2.mode, V4l2Mode::kSideBySide);
  EXPECT_EQ(sbs.source_config.v4l2.width, 2560);
  EXPECT_TRUE(sbs.stereo_depth.has_value());
  const CaptureConfig d415 = load("realsense_d415_uvc.yaml");
  EXPECT_EQ(d415.source_config.v4l2.mode, V4l2Mode::kDepth);
  EXPECT_EQ(d415.source_config.v4l2.depth_scale_m, 0.001);
  ASSERT_TRUE(d415.source_config.v4l2.depth_intrinsics.has_value());
  EXPECT_EQ(d415.source_config.v4l2.depth_intrinsics->fx, 423.0);
  EXPECT_EQ(d415.source_config.v4l2.T_B_D.translation().y(), 0.06);
  EXPECT_FALSE(d415.publish_stereo);
  const CaptureConfig ir_pair = load("realsense_ir_pair_uvc.yaml");
  EXPECT_EQ(ir_pair.source.rfind("v4l2:/dev/video", 0), 0u);
  EXPECT_EQ(ir_pair.source_config.v4l2.mode, V4l2Mode::kSideBySide);
  EXPECT_EQ(ir_pair.source_config.v4l2.pixel_format, "Y8I");
  EXPECT_EQ(ir_pair.source_config.v4l2.width, 848);
  EXPECT_EQ(ir_pair.source_config.v4l2.height, 480);
  EXPECT_EQ(ir_pair.source_config.v4l2.cameraWidth(), 848);  // interleaved: full-width views
  EXPECT_EQ(ir_pair.source_config.calibration_file, "/etc/cblox/calibration/d415_ir_camchain.yaml");
  EXPECT_TRUE(ir_pair.publish_stereo);
  EXPECT_FALSE(ir_pair.stereo_depth.has_value());  // the D4xx's depth node gives depth
  const CaptureConfig csi = load("csi_libcamera.yaml");
  EXPECT_EQ(csi.source, "libcamera:0");
  EXPECT_EQ(csi.source_config.libcamera.mode, LibcameraStereoMode::kSideBySide);
  EXPECT_EQ(csi.source_config.libcamera.camera.height, 800);
}

TEST(CaptureConfigTest, ReadsOverridesAndPresets) {
  const CaptureConfig config = loadCaptureConfig(YAML::Load(
      "source: euroc:/data\nrate: 10\nframes: 5\ndepth_encoding: f32\n"
      "channels: {stereo: S}\npublish: {depth: false}\n"
      "sim: {rig: {width: 320, right_cx_error_px: 1.5, T_L_D_position: [0.05, 0, 0]}, "
      "noise: {preset: realistic, "
      "image_noise_sigma: 3}}\n"));
  EXPECT_EQ(config.source, "euroc:/data");
  EXPECT_EQ(config.pacing, CapturePacing::kFixed);
  EXPECT_EQ(config.fixed_rate_hz, 10.0);
  EXPECT_EQ(config.source_config.max_frames, 5u);
  EXPECT_EQ(config.depth_encoding, DepthEncoding::kFloat32Metres);
  EXPECT_EQ(config.stereo_channel, "S");
  EXPECT_FALSE(config.publish_depth);
  EXPECT_EQ(config.source_config.sim.renderer.rig.stereo.width, 320);
  EXPECT_EQ(config.source_config.sim.renderer.rig.T_L_D.translation().x(), 0.05);
  EXPECT_EQ(config.source_config.sim.renderer.rig.right_cx_error_px, 1.5);
  EXPECT_EQ(config.source_config.sim.noise.image_noise_sigma, 3.0);
  EXPECT_EQ(config.source_config.sim.noise.depth_noise_per_m2, 0.0012);  // from the preset
}

TEST(CaptureConfigTest, RejectsBadKeysAndValuesNamingThem) {
  struct Case {
    const char* yaml;
    const char* message;
  };
  const Case cases[] = {
      {"sorce: sim:room\n", "sorce"},
      {"rate: fast\n", "rate must be 'source', 'max' or a rate in Hz"},
      {"frames: -1\n", "capture.frames"},
      {"depth_encoding: u8\n", "depth_encoding"},
      {"sim: {noise: {preset: noisy}}\n", "noise preset"},
      {"sim: {rig: {baseline_m: -1}}\n", "baseline_m"},
      {"sim: {rig: {right_cx_error_px: 11}}\n", "right_cx_error_px"},
      {"sim: {noise: {depth_hole_probability: 2}}\n", "depth_hole_probability"},
      {"channels: {sterio: X}\n", "sterio"},
      {"laps: 0\n", "laps"},
      {"stereo_depth: {matcher: census}\n", "stereo_depth.matcher"},
      {"stereo_depth: {matcher: sgbm, num_disparities: 50}\n", "stereo_depth.num_disparities"},
      {"stereo_depth: {max_rate_hz: -1}\n", "stereo_depth.max_rate_hz"},
      {"stereo_depth: {blocksize: 5}\n", "blocksize"},
      {"v4l2: {mode: quad}\n", "v4l2.mode"},
      {"v4l2: {pixel_format: H264}\n", "v4l2"},
      {"v4l2: {buffer_count: 1}\n", "buffer_count"},
      {"v4l2: {depth_intrinsics: {width: 640}}\n", "v4l2.depth_intrinsics.height"},
      {"v4l2: {exposure: fast}\n", "capture"},
      {"libcamera: {mode: triple}\n", "libcamera.mode"},
      {"libcamera: {width: 0}\n", "libcamera"},
      {"libcamera: {isp: on}\n", "isp"},
      {"device_wait_s: -1\n", "device_wait_s"},
      {"v4l2: {T_B_D_position: [1, 2]}\n", "T_B_D_position needs 3 numbers"},
      {"v4l2: {T_B_D_quaternion_wxyz: [2, 0, 0, 0]}\n", "v4l2.T_B_D_quaternion_wxyz: norm"},
  };
  for (const Case& c : cases) {
    try {
      loadCaptureConfig(YAML::Load(c.yaml));
      ADD_FAILURE() << "accepted: " << c.yaml;
    } catch (const ConfigError& e) {
      EXPECT_NE(std::string(e.what()).find(c.message), std::string::npos)
          << c.yaml << " -> " << e.what();
    }
  }
}

}  // namespace
}  // namespace cblox
