#include "core/mapping/planning_export.h"

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include "core/mapping/trajectory_log.h"
#include "test/mapping/wall_scene.h"
#include "test/test_support/temp_dir.h"

namespace cblox {
namespace {

constexpr float kVoxel = test::kWallVoxel;


class PlanningExportTest : public ::testing::Test {
 protected:
  test::WallScene scene_;
  PlanningMap* planning_ = &scene_.planning;
  test::TempDir dir_;
};

TEST_F(PlanningExportTest, GridPlyHoldsTheObservedCellsWithTheirDistances) {
  const MapperReply r = exportDistanceGrid(*planning_, {0.2, -0.1, -0.1}, {0.8, 0.1, 0.1}, 0.1,
                                           dir_.path(), "grid.ply");
  ASSERT_TRUE(r.ok) << r.message;
  EXPECT_EQ(r.value("cells"), "24");  // 6 x 2 x 2
  EXPECT_EQ(r.value("unknown"), "0");
  EXPECT_EQ(r.value("occupied"), "4");  // the x = 0.25 column
  std::ifstream in(dir_.path() / "grid.ply", std::ios::binary);
  std::string line, header;
  while (std::getline(in, line) && line != "end_header") header += line + "\n";
  EXPECT_NE(header.find("element vertex 24"), std::string::npos);
  EXPECT_NE(header.find("property float distance"), std::string::npos);
  // 24 vertices of 3 floats, 3 colour bytes, a float and a state byte.
  std::vector<char> body((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  ASSERT_EQ(body.size(), 24u * 20u);
  bool found = false;
  for (size_t v = 0; v < 24; ++v) {
    float xyz[3], distance;
    std::memcpy(xyz, &body[v * 20], 12);
    std::memcpy(&distance, &body[v * 20 + 15], 4);
    const uint8_t state = static_cast<uint8_t>(body[v * 20 + 19]);
    EXPECT_EQ(state, xyz[0] < 0.31f ? 2 : 1);
    if (std::abs(xyz[0] - 0.55f) < 1e-5f) {
      EXPECT_NEAR(distance, 0.24f, 1e-4f);
      found = true;
    }
  }
  EXPECT_TRUE(found);
}

TEST_F(PlanningExportTest, GridRefusesBadBoxesAndPathsOutsideTheOutputDirectory) {
  EXPECT_FALSE(exportDistanceGrid(*planning_, {0, 0, 0}, {0, 1, 1}, 0.1, dir_.path(), "g.ply").ok);
  EXPECT_FALSE(exportDistanceGrid(*planning_, {0, 0, 0}, {1e4, 1e4, 1e4}, 0.01, dir_.path(),
                                  "g.ply").ok);
  EXPECT_FALSE(exportDistanceGrid(*planning_, {0, 0, 0}, {1, 1, 1}, 0.0, dir_.path(), "g.ply").ok);
  EXPECT_FALSE(exportDistanceGrid(*planning_, {0, 0, 0}, {1, 1, 1}, 0.1, dir_.path(),
                                  "../g.ply").ok);
  EXPECT_FALSE(std::filesystem::exists(dir_.path() / "g.ply"));
}

TEST_F(PlanningExportTest, SliceIsAPictureOfTheFieldWithTheTrajectory) {
  const std::vector<Eigen::Vector3d> path = {{0.6, -0.2, 0.0}, {1.2, 0.0, 0.0}, {1.4, 0.3, 0.0}};
  const MapperReply r = exportDistanceSlice(*planning_, 0.0, kVoxel, path, dir_.path(), "s.png");
  ASSERT_TRUE(r.ok) << r.message;
  const cv::Mat png = cv::imread((dir_.path() / "s.png").string(), cv::IMREAD_COLOR);
  ASSERT_FALSE(png.empty());
  const int w = std::stoi(r.value("width")), h = std::stoi(r.value("height"));
  // The fields' extent: the blocks of 0.4 m that hold x in [-0.4, 1.6] and y in [-0.4, 0.4]
  // ([-0.4, 2.0) x [-0.4, 0.8)), grown by half a block's diagonal (0.346 m) on each side.
  const Eigen::AlignedBox3d bounds = planning_->boundsG();
  EXPECT_NEAR(bounds.min().x(), -0.4 - 0.2 * std::sqrt(3.0) + 0.2, 1e-6);  // float voxel size
  EXPECT_NEAR(bounds.max().y(), 0.8 + 0.2 * std::sqrt(3.0) - 0.2, 1e-6);
  EXPECT_EQ(w, static_cast<int>(std::ceil((bounds.max().x() - bounds.min().x()) / kVoxel - 1e-6)));
  EXPECT_EQ(h, static_cast<int>(std::ceil((bounds.max().y() - bounds.min().y()) / kVoxel - 1e-6)));
  // Cells of 8 x 8 pixels (the most).
  constexpr int kScale = 8;
  EXPECT_EQ(png.cols, 10 + kScale * w + 90);
  EXPECT_EQ(png.rows, 52 + kScale * h + 10);
  // Left of the wall black (occupied near the surface) or grey (unknown deeper inside);
  // right of it coloured (free). The pixel at the centre of the cell holding (x, y).
  const auto at = [&](double x, double y) {
    const int i = static_cast<int>((x - bounds.min().x()) / kVoxel);
    const int j = static_cast<int>((y - bounds.min().y()) / kVoxel);
    return png.at<cv::Vec3b>(52 + kScale * (h - 1 - j) + kScale / 2,
                             10 + kScale * i + kScale / 2);  // BGR
  };
  EXPECT_EQ(at(0.27, 0.1), cv::Vec3b(0, 0, 0));
  EXPECT_EQ(at(-0.3, 0.1), cv::Vec3b(128, 128, 128));
  const cv::Vec3b free = at(0.9, -0.35);
  EXPECT_NE(free, cv::Vec3b(0, 0, 0));
  EXPECT_NE(free, cv::Vec3b(128, 128, 128));
  EXPECT_EQ(r.value("resolution"), "0.0500");
  // An empty map: nothing to draw.
  PlanningMap empty(planning_->config());
  EXPECT_FALSE(exportDistanceSlice(empty, 0.0, kVoxel, path, dir_.path(), "e.png").ok);
}

TEST(TrajectoryLogTest, PositionsFollowTheirSubvolumesPoses) {
  TrajectoryLog log(100, 0.05);
  log.add(1, {0.0, 0.0, 0.0});
  log.add(1, {0.01, 0.0, 0.0});  // under the step: not kept
  log.add(1, {0.5, 0.0, 0.0});
  log.add(2, {0.0, 0.0, 0.0});
  log.add(3, {1.0, 1.0, 1.0});
  EXPECT_EQ(log.size(), 4u);
  SubmapPose a, b;
  a.id = 1;
  a.T_G_M = Transformationd(Eigen::Quaterniond::Identity(), Eigen::Vector3d(10, 0, 0));
  b.id = 2;
  b.T_G_M = Transformationd(Eigen::Quaterniond(Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ())),
                            Eigen::Vector3d(0, 5, 0));
  // Subvolume 3 is gone (fused away): its position is left out.
  const std::vector<Eigen::Vector3d> g = log.positionsG({a, b});
  ASSERT_EQ(g.size(), 3u);
  EXPECT_TRUE(g[0].isApprox(Eigen::Vector3d(10, 0, 0)));
  EXPECT_TRUE(g[1].isApprox(Eigen::Vector3d(10.5, 0, 0)));
  EXPECT_TRUE(g[2].isApprox(Eigen::Vector3d(0, 5, 0)));
}

TEST(TrajectoryLogTest, AFullLogKeepsTheWholePathCoarser) {
  TrajectoryLog log(10, 0.0);
  for (int i = 0; i < 25; ++i) log.add(1, {static_cast<double>(i), 0.0, 0.0});
  EXPECT_LE(log.size(), 10u);
  SubmapPose p;
  p.id = 1;
  const std::vector<Eigen::Vector3d> g = log.positionsG({p});
  ASSERT_FALSE(g.empty());
  EXPECT_EQ(g.front().x(), 0.0);  // the start stays
  EXPECT_EQ(g.back().x(), 24.0);  // and the newest
  for (size_t i = 1; i < g.size(); ++i) EXPECT_LT(g[i - 1].x(), g[i].x());
  EXPECT_THROW(TrajectoryLog(1, 0.0), std::invalid_argument);
}

}  // namespace
}  // namespace cblox
