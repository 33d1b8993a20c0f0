#include "drivers/open_frame_source.h"

#include <filesystem>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "core/io/ply_io.h"
#include "core/mesh/primitive_meshes.h"
#include "drivers/dataset/tum_rgbd_reader.h"
#include "drivers/frame_folder_writer.h"
#include "test/test_support/temp_dir.h"

namespace cblox {
namespace {

namespace fs = std::filesystem;

const std::string kData = CBLOX_SHARED_DATA_DIR;

class OpenFrameSourceTest : public testing::Test {
 protected:
  test::TempDir dir_{"cblox_sources"};
};

SourceConfig smallSim(size_t frames) {
  SourceConfig options;
  options.sim.renderer.rig.stereo = PinholeIntrinsics{160.0, 160.0, 79.5, 59.5, 160, 120};
  options.max_frames = frames;
  return options;
}

TEST_F(OpenFrameSourceTest, BuiltinSimScenesPlayWithGroundTruth) {
  for (const char* spec : {"sim:room", "sim:hall", "sim:town"}) {
    std::string error;
    auto source = openFrameSource(spec, smallSim(2), &error);
    ASSERT_NE(source, nullptr) << spec << ": " << error;
    EXPECT_EQ(source->info().name, std::string(spec) + "/loop");
    EXPECT_TRUE(source->info().has_ground_truth);
    ASSERT_TRUE(source->info().stereo.has_value());
    EXPECT_EQ(*source->info().frame_count, 2u);
    CaptureFrame frame;
    ASSERT_EQ(source->next(&frame, &error), FrameSource::Status::kFrame) << error;
    EXPECT_EQ(frame.left.width, 160);
    EXPECT_TRUE(frame.T_G_C.has_value());
    int valid = 0;
    for (float d : frame.depth.data) valid += d > 0.0f;
    EXPECT_GT(valid, 160 * 120 / 3) << spec;  // the town has sky above the horizon
  }
}

TEST_F(OpenFrameSourceTest, MeshFileWithOrbitOrTumTrajectory) {
  Mesh mesh;
  appendBox(&mesh, Eigen::AlignedBox3f(Eigen::Vector3f(-1, -1, 0), Eigen::Vector3f(1, 1, 1)),
            Color{200, 100, 50});
  const std::string ply = dir_.file("box.ply");
  std::string error;
  ASSERT_TRUE(writePly(ply, mesh, PlyFormat::kBinaryLittleEndian, &error)) << error;
  SourceConfig options = smallSim(3);
  options.trajectory = "orbit";
  auto source = openFrameSource("sim:" + ply, options, &error);
  ASSERT_NE(source, nullptr) << error;
  CaptureFrame frame;
  ASSERT_EQ(source->next(&frame, &error), FrameSource::Status::kFrame);
  EXPECT_GT(frame.depth(80, 60), 0.0f);  // looks at the box

  // A TUM trajectory file: two poses 1 s apart looking at the box from -y.
  const std::string tum = dir_.write("path.txt",
                                     "0 0 -5 0.5 -0.7071067811865476 0 0 0.7071067811865476\n"
                                     "1 0.5 -5 0.5 -0.7071067811865476 0 0 0.7071067811865476\n");
  options.trajectory = tum;
  options.sim.rate_hz = 10.0;
  options.max_frames = 0;
  source = openFrameSource("sim:" + ply, options, &error);
  ASSERT_NE(source, nullptr) << error;
  EXPECT_EQ(*source->info().frame_count, 11u);
  ASSERT_EQ(source->next(&frame, &error), FrameSource::Status::kFrame);
  // Camera at y = -5 looking along +y (R maps z_C to +y): the box face y = -1 is 4 m away.
  EXPECT_NEAR(frame.depth(80, 60), 4.0f, 1e-5f);

  options.trajectory = "loop";  // a mesh file has no built-in loop
  EXPECT_EQ(openFrameSource("sim:" + ply, options, &error), nullptr);
  EXPECT_NE(error.find("needs --trajectory orbit or a TUM file"), std::string::npos) << error;
}

TEST_F(OpenFrameSourceTest, NonManifoldScanOpensWithAWarning) {
  // A box plus a double-sided quad above it (as scanners export thin surfaces): the quad's
  // diagonal is used by four triangles, one non-manifold edge.
  Mesh mesh;
  appendBox(&mesh, Eigen::AlignedBox3f(Eigen::Vector3f(-1, -1, 0), Eigen::Vector3f(1, 1, 1)),
            Color{200, 100, 50});
  const int a = static_cast<int>(mesh.numVertices());
  mesh.vertices.insert(mesh.vertices.end(), {{-1, -1, 2}, {1, -1, 2}, {1, 1, 2}, {-1, 1, 2}});
  mesh.colors.resize(mesh.numVertices(), Color{90, 90, 90});
  mesh.triangles.insert(
      mesh.triangles.end(),
      {{a, a + 1, a + 2}, {a, a + 2, a + 3}, {a, a + 2, a + 1}, {a, a + 3, a + 2}});
  const std::string ply = dir_.file("scan.ply");
  std::string error;
  ASSERT_TRUE(writePly(ply, mesh, PlyFormat::kBinaryLittleEndian, &error)) << error;
  SourceConfig options = smallSim(2);
  options.trajectory = "orbit";
  std::vector<std::string> warnings;
  auto source = openFrameSource("sim:" + ply, options, &error, &warnings);
  ASSERT_NE(source, nullptr) << error;
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_NE(warnings[0].find("1 non-manifold edge(s)"), std::string::npos) << warnings[0];
  bool noted = false;
  for (const std::string& note : source->info().notes) {
    noted = noted || note == "warning: " + warnings[0];
  }
  EXPECT_TRUE(noted) << "the warning is not in info().notes";
  CaptureFrame frame;
  EXPECT_EQ(source->next(&frame, &error), FrameSource::Status::kFrame) << error;

  std::vector<std::string> mesh_warnings;
  EXPECT_NE(loadSimSceneMesh("sim:" + ply, &error, &mesh_warnings), nullptr) << error;
  EXPECT_EQ(mesh_warnings, warnings);
}

TEST_F(OpenFrameSourceTest, RenderedFolderReadsBackAsTumRgbd) {
  std::string error;
  auto source = openFrameSource("sim:room", smallSim(4), &error);
  ASSERT_NE(source, nullptr) << error;
  FrameFolderWriter writer;
  const std::string folder = dir_.file("render");
  ASSERT_TRUE(writer.open(folder, source->info(), &error)) << error;
  std::vector<CaptureFrame> frames;
  CaptureFrame frame;
  while (source->next(&frame, &error) == FrameSource::Status::kFrame) {
    ASSERT_TRUE(writer.write(frame, &error)) << error;
    frames.push_back(frame);
  }
  ASSERT_TRUE(writer.close(&error)) << error;
  for (const char* file : {"rgb.txt", "depth.txt", "left.txt", "right.txt", "groundtruth.txt",
                           "camera-intrinsics.txt", "stereo.yaml", "source.txt"}) {
    EXPECT_TRUE(fs::exists(fs::path(folder) / file)) << file;
  }
  // Read it back through the TUM RGB-D source.
  auto tum = openFrameSource("tum:" + folder, SourceConfig{}, &error);
  ASSERT_NE(tum, nullptr) << error;
  EXPECT_EQ(tum->info().depth_intrinsics->fx, 160.0);
  EXPECT_EQ(tum->info().depth_intrinsics->width, 160);
  for (const CaptureFrame& original : frames) {
    CaptureFrame back;
    ASSERT_EQ(tum->next(&back, &error), FrameSource::Status::kFrame) << error;
    EXPECT_NEAR(back.timestamp_ns, original.timestamp_ns, 1000);  // microsecond stamps
    ASSERT_TRUE(back.T_G_C.has_value());
    EXPECT_TRUE(back.T_G_C->isApprox(*original.T_G_C, 1e-9));
    ASSERT_EQ(back.depth.width, original.depth.width);
    for (size_t i = 0; i < back.depth.data.size(); ++i) {
      ASSERT_NEAR(back.depth.data[i], original.depth.data[i], 0.5f / 5000.0f + 1e-6f) << i;
    }
    EXPECT_EQ(back.color.data, original.color.data);
  }
  EXPECT_EQ(tum->next(&frame, &error), FrameSource::Status::kEnd);
}

TEST_F(OpenFrameSourceTest, DatasetFoldersFromSharedData) {
  if (!fs::is_directory(kData)) GTEST_SKIP() << "shared data not present at " << kData;
  std::string error;
  SourceConfig options;
  options.max_frames = 3;
  auto euroc = openFrameSource("euroc:" + kData + "/euroc-v101-micro", options, &error);
  ASSERT_NE(euroc, nullptr) << error;
  EXPECT_TRUE(euroc->info().stereo.has_value());
  EXPECT_FALSE(euroc->info().depth_intrinsics.has_value());
  EXPECT_FALSE(euroc->info().has_ground_truth);
  EXPECT_NEAR(euroc->info().rate_hz, 20.0, 1e-9);
  CaptureFrame frame;
  ASSERT_EQ(euroc->next(&frame, &error), FrameSource::Status::kFrame) << error;
  EXPECT_EQ(frame.timestamp_ns, 1403715273262142976LL);
  EXPECT_EQ(frame.left.width, 752);
  EXPECT_TRUE(frame.depth.empty());

  // KITTI: the grey pair, 10 Hz, camera 0's ground truth.
  auto kitti = openFrameSource("kitti:" + kData + "/kitti-odometry-51", options, &error);
  ASSERT_NE(kitti, nullptr) << error;
  ASSERT_TRUE(kitti->info().stereo.has_value());
  EXPECT_NEAR(kitti->info().stereo->baseline_m, 379.8145 / 707.0912, 1e-9);
  EXPECT_TRUE(kitti->info().has_ground_truth);
  EXPECT_NEAR(kitti->info().rate_hz, 10.0, 1e-9);
  EXPECT_EQ(kitti->info().frame_count, 3u);  // options.max_frames
  EXPECT_EQ(kitti->info().name, "kitti:" + kData + "/kitti-odometry-51");
  ASSERT_EQ(kitti->next(&frame, &error), FrameSource::Status::kFrame) << error;
  ASSERT_EQ(kitti->next(&frame, &error), FrameSource::Status::kFrame) << error;
  EXPECT_EQ(frame.frame_id, 1);
  EXPECT_EQ(frame.timestamp_ns, 100000000);
  EXPECT_EQ(frame.left.width, kitti->info().stereo->intrinsics.width);
  EXPECT_EQ(frame.right.height, kitti->info().stereo->intrinsics.height);
  EXPECT_TRUE(frame.depth.empty());
  ASSERT_TRUE(frame.T_G_C.has_value());
  EXPECT_NEAR(frame.T_G_C->translation().z(), 1.198998, 1e-9);

  auto scenes = openFrameSource("7scenes:" + kData + "/7scenes-rgbd-50", options, &error);
  ASSERT_NE(scenes, nullptr) << error;
  ASSERT_EQ(scenes->next(&frame, &error), FrameSource::Status::kFrame);
  ASSERT_EQ(scenes->next(&frame, &error), FrameSource::Status::kFrame);
  EXPECT_EQ(frame.frame_id, 1);
  EXPECT_EQ(frame.timestamp_ns, 33333333);
  EXPECT_EQ(frame.depth.width, 640);
  EXPECT_TRUE(frame.T_G_C.has_value());
}

// Camera specs without a camera attached: every refusal names what is wrong. No device is
// faked; the nodes named do not exist.
TEST_F(OpenFrameSourceTest, CameraSpecsRefusedWithReasons) {
  std::string error;
  EXPECT_EQ(openFrameSource("v4l2:/dev/video-cblox-absent", SourceConfig{}, &error), nullptr);
  EXPECT_NE(error.find("/dev/video-cblox-absent: no such device"), std::string::npos) << error;
  EXPECT_EQ(openFrameSource("v4l2-stereo:/dev/video0", SourceConfig{}, &error), nullptr);
  EXPECT_NE(error.find("needs two devices"), std::string::npos) << error;
  SourceConfig pair;
  pair.v4l2.mode = V4l2Mode::kStereoPair;
  EXPECT_EQ(openFrameSource("v4l2:/dev/video0", pair, &error), nullptr);
  EXPECT_NE(error.find("v4l2-stereo:L,R"), std::string::npos) << error;
  SourceConfig calibrated;
  calibrated.calibration_file = dir_.file("absent_camchain.yaml");
  EXPECT_EQ(openFrameSource("v4l2-stereo:/dev/video-a,/dev/video-b", calibrated, &error),
            nullptr);
  EXPECT_NE(error.find("absent_camchain.yaml: cannot open"), std::string::npos) << error;
  EXPECT_EQ(openFrameSource("libcamera:imx219", SourceConfig{}, &error), nullptr);
  EXPECT_NE(error.find("'imx219' not found; cameras present: "), std::string::npos) << error;
  // A calibration given to a source that carries its own is said, not used.
  SourceConfig sim = smallSim(1);
  sim.calibration_file = "rig.yaml";
  std::vector<std::string> warnings;
  EXPECT_NE(openFrameSource("sim:room", sim, &error, &warnings), nullptr) << error;
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_NE(warnings[0].find("calibration rig.yaml is for camera sources"), std::string::npos)
      << warnings[0];
}

TEST_F(OpenFrameSourceTest, RejectsUnknownSpecsAndMissingFolders) {
  std::string error;
  EXPECT_EQ(openFrameSource("room", SourceConfig{}, &error), nullptr);
  EXPECT_NE(error.find("has no kind"), std::string::npos) << error;
  EXPECT_EQ(openFrameSource("kinect:x", SourceConfig{}, &error), nullptr);
  EXPECT_NE(error.find("unknown source kind 'kinect'"), std::string::npos) << error;
  EXPECT_EQ(openFrameSource("sim:moon.ply", SourceConfig{}, &error), nullptr);
  EXPECT_NE(error.find("moon.ply"), std::string::npos) << error;
  EXPECT_EQ(openFrameSource("euroc:/nonexistent", SourceConfig{}, &error), nullptr);
  EXPECT_NE(error.find("/nonexistent"), std::string::npos) << error;
  EXPECT_EQ(openFrameSource("kitti:/nonexistent", SourceConfig{}, &error), nullptr);
  EXPECT_NE(error.find("/nonexistent: not a folder"), std::string::npos) << error;
  SourceConfig bad;
  bad.trajectory = "spiral";
  EXPECT_EQ(openFrameSource("sim:room", bad, &error), nullptr);
  EXPECT_NE(error.find("unknown trajectory 'spiral'"), std::string::npos) << error;
}

}  // namespace
}  // namespace cblox
