#include "core/mapping/planning_service.h"

#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <limits>
#include <mutex>
#include <optional>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "test/mapping/wall_scene.h"

namespace cblox {
namespace {

using namespace std::chrono_literals;

/// What the sinks received, with a wait for the n-th reply or grid.
struct Received {
  std::mutex mutex;
  std::condition_variable changed;
  std::vector<DistanceReply> replies;
  std::vector<LocalGridSample> grids;

  void addReply(const DistanceReply& r) {
    std::lock_guard<std::mutex> lock(mutex);
    replies.push_back(r);
    changed.notify_all();
  }
  void addGrid(const LocalGridSample& g) {
    std::lock_guard<std::mutex> lock(mutex);
    grids.push_back(g);
    changed.notify_all();
  }
  bool waitReplies(size_t n) {
    std::unique_lock<std::mutex> lock(mutex);
    return changed.wait_for(lock, 10s, [&] { return replies.size() >= n; });
  }
  bool waitGrids(size_t n) {
    std::unique_lock<std::mutex> lock(mutex);
    return changed.wait_for(lock, 10s, [&] { return grids.size() >= n; });
  }
};

/// The wall scene (wall_scene.h) and a service over it.
class PlanningServiceTest : public ::testing::Test {
 protected:
  std::unique_ptr<PlanningService> start(const PlanningServiceConfig& config,
                                         const PlanningMap* planning) {
    return std::make_unique<PlanningService>(
        config, planning, [this] { return epoch_.load(); },
        [this]() -> std::optional<std::pair<int64_t, Transformationd>> {
          return std::make_pair(int64_t{1234},
                                Transformationd(Eigen::Quaterniond::Identity(), vehicle_));
        },
        [this](const DistanceReply& r) { received_.addReply(r); },
        [this](const LocalGridSample& g) { received_.addGrid(g); });
  }
  static PlanningServiceConfig noGrid() {
    PlanningServiceConfig c;
    c.grid_period_s = 0.0;
    return c;
  }
  static void submit(PlanningService* service, int64_t id, int64_t epoch,
                     const std::vector<Eigen::Vector3d>& points) {
    service->submit(id, epoch, points.size(), [&](size_t k) { return points[k]; });
  }

  test::WallScene scene_;
  PlanningMap* planning_ = &scene_.planning;
  std::atomic<int64_t> epoch_{1000};
  Eigen::Vector3d vehicle_{0.52, 0.01, 0.0};
  Received received_;
};

TEST_F(PlanningServiceTest, AnswersEachPointWithStateDistanceAndGradient) {
  auto service = start(noGrid(), planning_);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  submit(service.get(), 7, 0,
         {{0.72, 0.013, -0.02}, {nan, 0.0, 0.0}, {1e6, -1e6, 1e6}, {0.2, 0.0, 0.0}});
  ASSERT_TRUE(received_.waitReplies(1));
  const DistanceReply& r = received_.replies[0];
  EXPECT_EQ(r.request_id, 7);
  EXPECT_EQ(r.map_epoch, 1000);
  EXPECT_EQ(r.status, DistanceStatus::kOk);
  EXPECT_EQ(r.max_distance_m, 1.0f);
  ASSERT_EQ(r.answers.size(), 4u);
  ASSERT_EQ(r.invalid_point, (std::vector<uint8_t>{0, 1, 0, 0}));
  // Free, exactly 0.41 m from the wall, gradient along +x: what query() says.
  EXPECT_EQ(r.answers[0].state, VoxelState::kFree);
  EXPECT_NEAR(r.answers[0].distance, 0.41, 1e-5);
  ASSERT_TRUE(r.answers[0].has_gradient);
  EXPECT_NEAR(r.answers[0].gradient.x(), 1.0, 1e-4);
  // The non-finite point is unknown with no distance; the far one unknown (no subvolume).
  EXPECT_EQ(r.answers[1].state, VoxelState::kUnknown);
  EXPECT_TRUE(std::isnan(r.answers[1].distance));
  EXPECT_EQ(r.answers[2].state, VoxelState::kUnknown);
  EXPECT_TRUE(std::isnan(r.answers[2].distance));
  // Behind the surface: occupied, negative.
  EXPECT_EQ(r.answers[3].state, VoxelState::kOccupied);
  EXPECT_LT(r.answers[3].distance, 0.0);
  const PlanningServiceStats s = service->stats();
  EXPECT_EQ(s.requests_answered, 1u);
  EXPECT_EQ(s.points_answered, 4u);
  EXPECT_EQ(s.requests_refused, 0u);
}

TEST_F(PlanningServiceTest, AnotherEpochIsAnsweredAndSaidSo) {
  auto service = start(noGrid(), planning_);
  submit(service.get(), 1, 1000, {{0.72, 0.0, 0.0}});
  submit(service.get(), 2, 999, {{0.72, 0.0, 0.0}});
  ASSERT_TRUE(received_.waitReplies(2));
  EXPECT_EQ(received_.replies[0].status, DistanceStatus::kOk);
  EXPECT_EQ(received_.replies[1].status, DistanceStatus::kEpochChanged);
  EXPECT_NE(received_.replies[1].message.find("999"), std::string::npos);
  ASSERT_EQ(received_.replies[1].answers.size(), 1u);
  EXPECT_EQ(received_.replies[1].answers[0].state, VoxelState::kFree);
  EXPECT_EQ(received_.replies[1].map_epoch, 1000);
}

TEST_F(PlanningServiceTest, TooManyPointsIsRefusedBeforeAnyPointIsRead) {
  PlanningServiceConfig c = noGrid();
  c.max_points = 8;
  auto service = start(c, planning_);
  size_t reads = 0;
  service->submit(5, 0, 9, [&](size_t) {
    ++reads;
    return Eigen::Vector3d::Zero();
  });
  // Answered on this thread, at once.
  ASSERT_EQ(received_.replies.size(), 1u);
  EXPECT_EQ(received_.replies[0].status, DistanceStatus::kTooManyPoints);
  EXPECT_TRUE(received_.replies[0].answers.empty());
  EXPECT_EQ(reads, 0u);
  service->submit(6, 0, size_t{1} << 40, [&](size_t) {
    ++reads;
    return Eigen::Vector3d::Zero();
  });
  ASSERT_EQ(received_.replies.size(), 2u);
  EXPECT_EQ(reads, 0u);
  EXPECT_EQ(service->stats().requests_refused, 2u);
}

TEST_F(PlanningServiceTest, WithoutAPlanningMapEveryRequestSaysSo) {
  auto service = start(noGrid(), nullptr);
  submit(service.get(), 3, 0, {{0.0, 0.0, 0.0}});
  ASSERT_TRUE(received_.waitReplies(1));
  EXPECT_EQ(received_.replies[0].status, DistanceStatus::kNoPlanningMap);
  EXPECT_NE(received_.replies[0].message.find("planning.enabled"), std::string::npos);
  EXPECT_TRUE(received_.replies[0].answers.empty());
}

TEST_F(PlanningServiceTest, AFullQueueAnswersBusy) {
  PlanningServiceConfig c = noGrid();
  c.queue_capacity = 2;
  // The first reply blocks the worker until released: the queue then fills.
  std::mutex gate_mutex;
  std::condition_variable gate;
  bool open = false, first_in_sink = false;
  PlanningService service(
      c, planning_, [] { return int64_t{1}; },
      [] { return std::optional<std::pair<int64_t, Transformationd>>(); },
      [&](const DistanceReply& r) {
        if (r.request_id == 1) {
          std::unique_lock<std::mutex> lock(gate_mutex);
          first_in_sink = true;
          gate.notify_all();
          gate.wait(lock, [&] { return open; });
        }
        received_.addReply(r);
      },
      nullptr);
  submit(&service, 1, 0, {{0.72, 0.0, 0.0}});
  {
    std::unique_lock<std::mutex> lock(gate_mutex);
    ASSERT_TRUE(gate.wait_for(lock, 10s, [&] { return first_in_sink; }));
  }
  submit(&service, 2, 0, {{0.72, 0.0, 0.0}});
  submit(&service, 3, 0, {{0.72, 0.0, 0.0}});
  submit(&service, 4, 0, {{0.72, 0.0, 0.0}});  // the third waiting: refused at once
  ASSERT_TRUE(received_.waitReplies(1));
  EXPECT_EQ(received_.replies[0].request_id, 4);
  EXPECT_EQ(received_.replies[0].status, DistanceStatus::kBusy);
  {
    std::lock_guard<std::mutex> lock(gate_mutex);
    open = true;
  }
  gate.notify_all();
  ASSERT_TRUE(received_.waitReplies(4));
  EXPECT_EQ(received_.replies[1].request_id, 1);
  EXPECT_EQ(received_.replies[2].request_id, 2);
  EXPECT_EQ(received_.replies[3].request_id, 3);
  EXPECT_EQ(service.stats().requests_answered, 3u);
  EXPECT_EQ(service.stats().requests_refused, 1u);
}

TEST_F(PlanningServiceTest, PublishesGridsAroundTheVehicleOnTheResolutionsLattice) {
  PlanningServiceConfig c;
  c.grid_period_s = 0.01;
  c.grid_size_m = Eigen::Vector3d(0.6, 0.4, 0.2);
  c.grid_resolution_m = 0.1;
  auto service = start(c, planning_);
  ASSERT_TRUE(received_.waitGrids(2));
  service.reset();
  const LocalGridSample& g = received_.grids[0];
  EXPECT_EQ(g.map_epoch, 1000);
  EXPECT_EQ(g.pose_utime, 1234);
  EXPECT_EQ(g.max_distance_m, 1.0f);
  // Centre (0.52, 0.01, 0): corner floor((centre - size / 2) / 0.1) * 0.1.
  EXPECT_NEAR(g.grid.origin.x(), 0.2, 1e-12);
  EXPECT_NEAR(g.grid.origin.y(), -0.2, 1e-12);
  EXPECT_NEAR(g.grid.origin.z(), -0.1, 1e-12);
  EXPECT_EQ(g.grid.size, Eigen::Vector3i(6, 4, 2));
  EXPECT_EQ(g.grid.resolution, 0.1);
  // Every cell is what the planning map says at its centre.
  for (int k = 0; k < 2; ++k) {
    for (int j = 0; j < 4; ++j) {
      for (int i = 0; i < 6; ++i) {
        const DistanceAnswer a = planning_->query(g.grid.cellCenter(i, j, k));
        const size_t cell = g.grid.index(i, j, k);
        EXPECT_EQ(g.grid.state[cell], a.state);
        if (a.state == VoxelState::kUnknown) {
          EXPECT_TRUE(std::isnan(g.grid.distance[cell]));
        } else {
          EXPECT_FLOAT_EQ(g.grid.distance[cell], static_cast<float>(a.distance));
        }
      }
    }
  }
  // The wall x < 0.31: cells centred at x = 0.25 are occupied, at 0.45 free 0.14 m away.
  EXPECT_EQ(g.grid.state[g.grid.index(0, 1, 1)], VoxelState::kOccupied);
  EXPECT_EQ(g.grid.state[g.grid.index(2, 1, 1)], VoxelState::kFree);
  EXPECT_NEAR(g.grid.distance[g.grid.index(2, 1, 1)], 0.14, 1e-4);
  EXPECT_GE(received_.grids.size(), 2u);
}

TEST(PlanningServiceConfigTest, RefusesBadSettingsNamingThem) {
  PlanningServiceConfig c;
  EXPECT_TRUE(c.validate().empty());
  c.grid_resolution_m = 0.0;
  EXPECT_NE(c.validate().find("grid_resolution_m"), std::string::npos);
  c = PlanningServiceConfig{};
  c.grid_size_m.y() = std::numeric_limits<double>::infinity();
  EXPECT_NE(c.validate().find("grid_size_m"), std::string::npos);
  c = PlanningServiceConfig{};
  c.grid_size_m = Eigen::Vector3d(1000.0, 1000.0, 10.0);
  EXPECT_NE(c.validate().find("cells"), std::string::npos);
  c = PlanningServiceConfig{};
  c.queue_capacity = 0;
  EXPECT_NE(c.validate().find("queue_capacity"), std::string::npos);
  c = PlanningServiceConfig{};
  c.grid_period_s = -1.0;
  EXPECT_NE(c.validate().find("grid_period_s"), std::string::npos);
}

}  // namespace
}  // namespace cblox
