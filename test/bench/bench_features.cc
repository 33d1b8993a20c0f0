// Google Benchmark: ORB-SLAM2-style feature extraction (cblox::OrbExtractor, 1200 features,
// scale 1.2, 8 levels) against OpenCV's ORB (cv::ORB::create(1200, 1.2f, 8)) on the same
// simulator frames, plus stereo matching and RGB-D depth of the extracted keypoints.
// Frames: sim:room (752x480 default rig, exact images), 8 poses 1 s apart along its loop,
// rendered once before timing. One iteration = one image (frames taken in turn). OpenCV's
// own worker threads are off (cv::setNumThreads(1)) so every figure is one core. Also FAST
// alone (cblox::FastDetector vs cv::FAST, thresholds 7 and 20, level-0 image).
//
//   build/test/bench/cblox-bench-features --benchmark_repetitions=15
//   --benchmark_report_aggregates_only=true
//
// The *_median rows are the figures to report (the host is shared); run it under
// `taskset -c 0` for one pinned core.

#include <benchmark/benchmark.h>

#include <cstdio>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>

#include "core/features/brief_blur.h"
#include "core/features/fast_detector.h"
#include "core/features/fast_grid_detector.h"
#include "core/features/orb_extractor.h"
#include "core/features/orb_orientation.h"
#include "core/features/quadtree_distribution.h"
#include "core/features/rgbd_depth.h"
#include "core/features/rotated_brief.h"
#include "core/features/stereo_matcher.h"
#include "core/vocabulary/binary_vocabulary.h"
#include "drivers/open_frame_source.h"

namespace cblox {
namespace {

struct Frames {
  std::vector<CaptureFrame> frames;
  double fx = 0.0, baseline_m = 0.0;
};

const Frames& frames() {
  static const Frames f = [] {
    Frames result;
    SourceConfig options;
    options.sim.rate_hz = 1.0;
    options.max_frames = 8;
    std::string error;
    std::unique_ptr<FrameSource> source = openFrameSource("sim:room", options, &error);
    if (source == nullptr || !source->info().stereo.has_value()) {
      std::fprintf(stderr, "cannot open sim:room: %s\n", error.c_str());
      std::exit(1);
    }
    result.fx = source->info().stereo->intrinsics.fx;
    result.baseline_m = source->info().stereo->baseline_m;
    CaptureFrame frame;
    while (source->next(&frame, &error) == FrameSource::Status::kFrame) {
      result.frames.push_back(frame);
    }
    if (result.frames.empty()) {
      std::fprintf(stderr, "sim:room delivered no frame: %s\n", error.c_str());
      std::exit(1);
    }
    return result;
  }();
  return f;
}

cv::Mat view(const GrayImage& image) {
  return cv::Mat(image.height, image.width, CV_8UC1, const_cast<uint8_t*>(image.data.data()));
}

void BM_OrbExtractor(benchmark::State& state) {
  const Frames& f = frames();
  OrbExtractor extractor{OrbExtractorConfig{}};
  size_t i = 0, features = 0, images = 0;
  for (auto _ : state) {
    const ExtractedFeatures out = extractor.extract(f.frames[i++ % f.frames.size()].left);
    features += out.keypoints.size();
    ++images;
    benchmark::DoNotOptimize(out.descriptors.data());
  }
  state.counters["features"] = static_cast<double>(features) / static_cast<double>(images);
}

void BM_CvOrb(benchmark::State& state) {
  const Frames& f = frames();
  cv::Ptr<cv::ORB> orb = cv::ORB::create(1200, 1.2f, 8);
  std::vector<cv::KeyPoint> keypoints;
  cv::Mat descriptors;
  size_t i = 0, features = 0, images = 0;
  for (auto _ : state) {
    orb->detectAndCompute(view(f.frames[i++ % f.frames.size()].left), cv::noArray(), keypoints,
                          descriptors);
    features += keypoints.size();
    ++images;
    benchmark::DoNotOptimize(descriptors.data);
  }
  state.counters["features"] = static_cast<double>(features) / static_cast<double>(images);
}

void BM_MatchStereo(benchmark::State& state) {
  const Frames& f = frames();
  OrbExtractor left{OrbExtractorConfig{}}, right{OrbExtractorConfig{}};
  std::vector<std::pair<ExtractedFeatures, ExtractedFeatures>> pairs;
  for (const CaptureFrame& frame : f.frames) {
    pairs.emplace_back(left.extract(frame.left), right.extract(frame.right));
  }
  size_t i = 0, matched = 0, images = 0;
  for (auto _ : state) {
    const auto& [l, r] = pairs[i++ % pairs.size()];
    const StereoDepth depth = matchStereo(l, r, f.fx, f.baseline_m, StereoMatcherConfig{});
    matched += depth.numWithDepth();
    ++images;
  }
  state.counters["matched"] = static_cast<double>(matched) / static_cast<double>(images);
}

void BM_DepthFromRgbd(benchmark::State& state) {
  const Frames& f = frames();
  OrbExtractor extractor{OrbExtractorConfig{}};
  std::vector<ExtractedFeatures> extracted;
  for (const CaptureFrame& frame : f.frames) extracted.push_back(extractor.extract(frame.left));
  size_t i = 0;
  for (auto _ : state) {
    const size_t k = i++ % extracted.size();
    const StereoDepth depth =
        depthFromRgbd(extracted[k].keypoints, f.frames[k].depth, f.fx * f.baseline_m);
    benchmark::DoNotOptimize(depth.depth.data());
  }
}

// FAST alone on the level-0 image: cblox::FastDetector against cv::FAST (identical corners).
void BM_FastDetector(benchmark::State& state) {
  const Frames& f = frames();
  FastDetector detector;
  std::vector<FastCorner> corners;
  size_t i = 0;
  for (auto _ : state) {
    detector.detect(view(f.frames[i++ % f.frames.size()].left), static_cast<int>(state.range(0)),
                    &corners);
    benchmark::DoNotOptimize(corners.data());
  }
}

void BM_CvFast(benchmark::State& state) {
  const Frames& f = frames();
  std::vector<cv::KeyPoint> corners;
  size_t i = 0;
  for (auto _ : state) {
    cv::FAST(view(f.frames[i++ % f.frames.size()].left), corners, static_cast<int>(state.range(0)),
             true);
    benchmark::DoNotOptimize(corners.data());
  }
}

// The stages of one extraction, each over all levels of the same images (the split of
// extract/cblox::OrbExtractor): the pyramid (cv::resize), FAST on the detection grid, the
// quadtree distribution, the blur before BRIEF, and orientation + rotated BRIEF of the kept
// corners.
struct StageInputs {
  std::vector<std::vector<cv::Mat>> pyramids;
  std::vector<std::vector<std::vector<LevelCorner>>> corners;
  std::vector<std::vector<std::vector<int>>> kept;
};

FastGridConfig stageGrid() {
  FastGridConfig grid;
  grid.edge_threshold = OrbExtractorConfig::kEdgeThreshold;
  grid.cell_size = OrbExtractorConfig::kCellSize;
  return grid;
}

const StageInputs& stageInputs() {
  static const StageInputs s = [] {
    StageInputs out;
    const OrbExtractor extractor{OrbExtractorConfig{}};
    FastGridDetector grid;
    constexpr int kMargin = OrbExtractorConfig::kEdgeThreshold - 3;
    for (const CaptureFrame& frame : frames().frames) {
      out.pyramids.push_back(extractor.scales().build(view(frame.left)));
      out.corners.emplace_back();
      out.kept.emplace_back();
      for (size_t l = 0; l < out.pyramids.back().size(); ++l) {
        const cv::Mat& img = out.pyramids.back()[l];
        out.corners.back().push_back(grid.detect(img, stageGrid()));
        out.kept.back().push_back(
            distributeQuadtree(out.corners.back().back(), kMargin, img.cols - kMargin, kMargin,
                               img.rows - kMargin, extractor.featuresPerLevel()[l]));
      }
    }
    return out;
  }();
  return s;
}

void BM_StagePyramid(benchmark::State& state) {
  const Frames& f = frames();
  const ScalePyramid scales(OrbExtractorConfig{}.num_levels, OrbExtractorConfig{}.scale_factor);
  size_t i = 0;
  for (auto _ : state) {
    std::vector<cv::Mat> pyramid = scales.build(view(f.frames[i++ % f.frames.size()].left));
    benchmark::DoNotOptimize(pyramid.data());
  }
}

void BM_StageFastGrid(benchmark::State& state) {
  const StageInputs& s = stageInputs();
  FastGridDetector grid;
  size_t i = 0;
  for (auto _ : state) {
    for (const cv::Mat& img : s.pyramids[i++ % s.pyramids.size()]) {
      std::vector<LevelCorner> corners = grid.detect(img, stageGrid());
      benchmark::DoNotOptimize(corners.data());
    }
  }
}

void BM_StageQuadtree(benchmark::State& state) {
  const StageInputs& s = stageInputs();
  const OrbExtractor extractor{OrbExtractorConfig{}};
  constexpr int kMargin = OrbExtractorConfig::kEdgeThreshold - 3;
  size_t i = 0;
  for (auto _ : state) {
    const size_t k = i++ % s.pyramids.size();
    for (size_t l = 0; l < s.pyramids[k].size(); ++l) {
      const cv::Mat& img = s.pyramids[k][l];
      std::vector<int> kept =
          distributeQuadtree(s.corners[k][l], kMargin, img.cols - kMargin, kMargin,
                             img.rows - kMargin, extractor.featuresPerLevel()[l]);
      benchmark::DoNotOptimize(kept.data());
    }
  }
}

// arg 0: BriefBlur::apply (AVX2 + FMA where the CPU has them), 1: applyOpenCv (cv::GaussianBlur
// as OpenCV's ORB calls it); the same bytes.
void BM_StageBlur(benchmark::State& state) {
  const StageInputs& s = stageInputs();
  BriefBlur blur;
  cv::Mat blurred;
  size_t i = 0;
  for (auto _ : state) {
    for (const cv::Mat& img : s.pyramids[i++ % s.pyramids.size()]) {
      if (state.range(0) == 0) {
        blur.apply(img, &blurred);
      } else {
        blur.applyOpenCv(img, &blurred);
      }
      benchmark::DoNotOptimize(blurred.data);
    }
  }
}

void BM_StageDescribe(benchmark::State& state) {
  const StageInputs& s = stageInputs();
  std::vector<std::vector<cv::Mat>> blurred(s.pyramids.size());
  for (size_t k = 0; k < s.pyramids.size(); ++k) {
    for (const cv::Mat& img : s.pyramids[k]) {
      BriefBlur blur;
      cv::Mat out;
      blur.apply(img, &out);
      blurred[k].push_back(out);
    }
  }
  const OrbOrientation orientation;
  const RotatedBrief brief;
  size_t i = 0;
  for (auto _ : state) {
    const size_t k = i++ % s.pyramids.size();
    for (size_t l = 0; l < s.pyramids[k].size(); ++l) {
      for (const int c : s.kept[k][l]) {
        const LevelCorner& corner = s.corners[k][l][static_cast<size_t>(c)];
        const float angle = orientation.angleDeg(s.pyramids[k][l], corner.x, corner.y);
        const OrbDescriptor d = brief.compute(blurred[k][l], static_cast<float>(corner.x),
                                              static_cast<float>(corner.y), angle);
        benchmark::DoNotOptimize(d);
      }
    }
  }
}

// BoW vectors of the extracted left images with the build-time vocabulary (DBoW2-style tree,
// k = 10, L = 6, 22 MB): arg 0 = BinaryVocabulary::transform (BoW and feature vector, 16
// descents interleaved), arg 1 = wordOf() for each descriptor in turn (one descent after the
// other: the words alone, without the vectors). Second arg: MB of memory written before each
// iteration (untimed), so that the vocabulary comes from memory rather than from the cache, as
// in the tracker, which touches other data between keyframes (this host's L3 is 260 MB; a NUC's
// is 6-12 MB).
const BinaryVocabulary* vocabulary() {
  static const std::optional<BinaryVocabulary> v = [] {
    std::string error;
    std::optional<BinaryVocabulary> loaded =
        BinaryVocabulary::load(CBLOX_DEFAULT_VOCABULARY, &error);
    if (!loaded) std::fprintf(stderr, "no vocabulary: %s\n", error.c_str());
    return loaded;
  }();
  return v ? &*v : nullptr;
}

void BM_BowTransform(benchmark::State& state) {
  const BinaryVocabulary* v = vocabulary();
  if (v == nullptr) {
    state.SkipWithError("the build-time vocabulary is missing");
    return;
  }
  const Frames& f = frames();
  OrbExtractor extractor{OrbExtractorConfig{}};
  std::vector<std::vector<OrbDescriptor>> descriptors;
  for (const CaptureFrame& frame : f.frames) {
    descriptors.push_back(extractor.extract(frame.left).descriptors);
  }
  BowVector bow;
  FeatureVector feature_vector;
  size_t i = 0;
  std::vector<char> junk(static_cast<size_t>(state.range(1)) << 20);
  for (auto _ : state) {
    if (!junk.empty()) {
      state.PauseTiming();
      for (size_t k = 0; k < junk.size(); k += 64) junk[k] += 1;
      benchmark::DoNotOptimize(junk.data());
      state.ResumeTiming();
    }
    const std::vector<OrbDescriptor>& d = descriptors[i++ % descriptors.size()];
    if (state.range(0) == 0) {
      v->transform(d, &bow, &feature_vector);
      benchmark::DoNotOptimize(bow.data());
    } else {
      for (const OrbDescriptor& one : d) benchmark::DoNotOptimize(v->wordOf(one));
    }
  }
}

BENCHMARK(BM_OrbExtractor)->Name("extract/cblox::OrbExtractor")->Unit(benchmark::kMillisecond);
BENCHMARK(BM_StagePyramid)->Name("stage/pyramid")->Unit(benchmark::kMillisecond);
BENCHMARK(BM_StageFastGrid)->Name("stage/fast_grid")->Unit(benchmark::kMillisecond);
BENCHMARK(BM_StageQuadtree)->Name("stage/quadtree")->Unit(benchmark::kMillisecond);
BENCHMARK(BM_StageBlur)->Name("stage/blur")->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_StageDescribe)->Name("stage/orientation+brief")->Unit(benchmark::kMillisecond);
BENCHMARK(BM_BowTransform)
    ->Name("bow/transform")
    ->Args({0, 0})
    ->Args({1, 0})
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_BowTransform)
    ->Name("bow/transform_cold")
    ->Args({0, 300})
    ->Args({1, 300})
    ->Iterations(100)
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_CvOrb)->Name("extract/cv::ORB")->Unit(benchmark::kMillisecond);
BENCHMARK(BM_MatchStereo)->Name("stereo/matchStereo")->Unit(benchmark::kMillisecond);
BENCHMARK(BM_DepthFromRgbd)->Name("rgbd/depthFromRgbd")->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_FastDetector)
    ->Name("fast/cblox::FastDetector")
    ->Arg(7)
    ->Arg(20)
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_CvFast)->Name("fast/cv::FAST")->Arg(7)->Arg(20)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace cblox

int main(int argc, char** argv) {
  cv::setNumThreads(1);
  cblox::frames();  // render before any timing
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
