// Smoke test of the documented thread-safety rule (SubmapCollection, Submap) under real
// concurrency; scripts/tsan.sh runs it with ThreadSanitizer. Threads as in the mapper:
// - integrator: integrates frames into the active submap under Submap::lockForIntegration;
// - maintenance: applies keyframe pose batches, adds keyframes, switches the active submap;
// - fusion worker: reads finished submaps (interpolation, meshing), fuses the oldest
//   finished submap into the next and removes it, projects the collection (taking the
//   active submap's layer lock), and reads statistics and pose snapshots.

#include <atomic>
#include <cmath>
#include <memory>
#include <thread>

#include <gtest/gtest.h>

#include "core/integrator/projective_tsdf_integrator.h"
#include "core/submap/submap_collection.h"
#include "core/submap/submap_fusion.h"
#include "core/tsdf/tsdf_interpolator.h"
#include "test/submap/submap_test_scene.h"

namespace cblox {
namespace {

constexpr int kFrames = 240;
constexpr int kFramesPerSubmap = 40;

PinholeIntrinsics tinyIntrinsics() { return {40.0, 40.0, 19.5, 14.5, 40, 30}; }

TEST(SubmapConcurrency, IntegrationPoseUpdatesAndFusionRunConcurrently) {
  const std::vector<SyntheticFrame> frames = test::renderOrbit(12, tinyIntrinsics());
  const PinholeCamera camera(tinyIntrinsics());
  SubmapCollectionConfig collection_config;
  collection_config.layer = LayerConfig{0.04f, 8};
  SubmapCollection collection(collection_config);
  collection.createSubmap(frames[0].T_G_C, 0, 0);

  std::atomic<int> frames_done{0};
  std::atomic<bool> stop{false};
  std::atomic<int> frames_integrated{0}, lock_refused{0}, fusions{0}, projections{0};
  std::atomic<int> created{1};  // submaps made (the first above)

  std::thread integrator_thread([&] {
    IntegratorConfig config = test::integratorConfig(/*num_threads=*/2);
    config.truncation_distance_m = 0.16f;
    std::shared_ptr<Submap> bound;  // the submap `integrator` writes (kept alive)
    std::unique_ptr<ProjectiveTsdfIntegrator> integrator;
    for (int i = 0; i < kFrames; ++i) {
      const SyntheticFrame& frame = frames[static_cast<size_t>(i) % frames.size()];
      for (int attempt = 0; attempt < 2; ++attempt) {
        const std::shared_ptr<Submap> active = collection.activeSubmap();
        if (!active) break;
        Submap::WriteLock lock = active->lockForIntegration();
        if (!lock) {  // finished since activeSubmap(): fetch the new one
          ++lock_refused;
          continue;
        }
        if (bound != active) {
          integrator = std::make_unique<ProjectiveTsdfIntegrator>(config, &lock.layer());
          bound = active;
        }
        integrator->integrateDepthImage(active->T_M_C(frame.T_G_C), frame.depth, camera,
                                        &frame.color);
        ++frames_integrated;
        break;
      }
      frames_done.store(i + 1);
    }
  });

  std::thread maintenance_thread([&] {
    KeyframeId next_keyframe = 1;
    int last_switch = 0;
    while (frames_done.load() < kFrames) {
      const int done = frames_done.load();
      std::vector<std::pair<KeyframeId, Transformationd>> batch;
      for (const SubmapPose& pose : collection.poseSnapshot()) {
        const Eigen::Vector3d nudge(1e-4 * std::sin(done), 1e-4 * std::cos(done), 0.0);
        batch.emplace_back(pose.anchor_keyframe, Transformationd(pose.T_G_M.rotation(),
                                                                 pose.T_G_M.translation() + nudge));
      }
      batch.emplace_back(-1, Transformationd());  // unknown keyframe
      collection.updateKeyframePoses(batch);
      if (const auto active = collection.activeSubmap()) active->addKeyframe(next_keyframe++);
      if (done - last_switch >= kFramesPerSubmap) {
        last_switch = done;
        const SyntheticFrame& frame = frames[static_cast<size_t>(done) % frames.size()];
        collection.createSubmap(frame.T_G_C, next_keyframe++, done);
        ++created;
      }
      std::this_thread::yield();
    }
  });

  std::thread worker_thread([&] {
    SubmapFusionConfig fusion_config;
    fusion_config.num_threads = 2;
    size_t observed_sum = 0;
    int round = 0;
    while (!stop.load()) {
      ++round;
      std::vector<std::shared_ptr<Submap>> finished;
      for (const auto& submap : collection.submaps()) {
        if (submap->isFinished()) finished.push_back(submap);
      }
      for (const auto& submap : finished) {
        // Reads of a finished layer: no lock (the worker owns finished submaps).
        for (const auto& [key, block] : submap->layer().blocks()) {
          observed_sum += static_cast<size_t>(block->countObservedVoxels());
        }
        const TsdfInterpolator interpolator(submap->layer());
        float distance = 0.0f;
        interpolator.getInterpolatedDistance(Eigen::Vector3f(0.5f, 0.0f, 0.0f), &distance);
        test::meshLayer(submap->layer());
      }
      if (finished.size() >= 3) {
        fuseSubmaps(*finished[0], finished[1].get(), fusion_config);
        collection.removeSubmap(finished[0]->id());
        ++fusions;
      }
      if (round % 4 == 0) {
        projectCollection(collection, collection.config().layer, fusion_config, true);
        ++projections;
      }
      collection.numBlocks();
      collection.memoryBytes();
      collection.poseSnapshot();
      std::this_thread::yield();
    }
    EXPECT_GE(observed_sum, 0u);
  });

  integrator_thread.join();
  maintenance_thread.join();
  stop.store(true);
  worker_thread.join();

  EXPECT_GT(frames_integrated.load(), kFrames / 2);
  // Every submap made is still there or was fused away (how many were made depends on
  // how the threads were scheduled; under load fewer switches happen).
  EXPECT_GE(created.load(), 2);
  EXPECT_EQ(collection.size() + static_cast<size_t>(fusions.load()),
            static_cast<size_t>(created.load()));
  EXPECT_GT(projections.load(), 0);
  const TsdfLayer map =
      projectCollection(collection, collection.config().layer, SubmapFusionConfig{});
  EXPECT_GT(map.numBlocks(), 10u);
  std::printf(
      "[ measured ] %d frames integrated, %d refused locks, %d fusions, %d projections, "
      "%zu submaps left\n",
      frames_integrated.load(), lock_refused.load(), fusions.load(), projections.load(),
      collection.size());
}

}  // namespace
}  // namespace cblox
