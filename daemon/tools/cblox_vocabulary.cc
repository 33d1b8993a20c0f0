// cblox-vocabulary: trains and inspects the binary (ORB) vocabulary used for place
// recognition (loop closing and relocalisation).
//
//   cblox-vocabulary train --source sim:yard --frames 400 --every 10 --out vocab.bin
//   cblox-vocabulary train --source sim:yard --trajectory loop,figure-eight,orbit,lawnmower
//       --frames 400 --every 10 --k 10 --levels 6 --out build/vocabulary/cblox_orb.vocab
//   cblox-vocabulary info vocab.bin
//
// train: plays the source, takes every K-th frame (simulator sources render only those: the
// simulated rate is divided by K), extracts ORB features of the left image with
// cblox::OrbExtractor, trains the vocabulary tree (hierarchical k-majority, idf from the
// training images) and writes it. Several comma-separated trajectories share the --frames
// budget equally. The simulator's texture seed defaults to 2 (the evaluation runs use 1), and
// the evaluation scenes sim:room, sim:hall and sim:town are refused unless
// --allow-evaluation-scene is given: a vocabulary must not be trained on what it is
// evaluated on.
// Exit status: 0 done, 1 runtime error, 2 usage error or unreadable/unwritable file.

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/common/text_format.h"
#include "core/features/orb_extractor.h"
#include "core/vocabulary/binary_vocabulary.h"
#include "daemon/capture/capture_config.h"
#include "daemon/common/cli.h"
#include "daemon/common/yaml_config.h"
#include "drivers/open_frame_source.h"
#include "drivers/sim/builtin_scenes.h"
#include "drivers/sim/sensor_model.h"
#include "drivers/sim/sim_renderer.h"

namespace cblox {
namespace {

using Clock = std::chrono::steady_clock;

/// A usage error or an unreadable/unwritable file: exit status 2.
struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

struct TrainArgs {
  std::string source;
  std::string out;
  std::vector<std::string> trajectories{"loop", "figure-eight", "orbit", "lawnmower"};
  int laps = 1;
  int frames = 400;
  int every = 10;
  std::string noise = "realistic";
  uint32_t texture_seed = 2;
  int features = 1200;
  BinaryVocabularyConfig vocabulary{.num_threads = 2};
  bool allow_evaluation_scene = false;
  bool quiet = false;
};

std::vector<std::string> splitCommas(const std::string& text) {
  std::vector<std::string> parts;
  std::stringstream stream(text);
  for (std::string part; std::getline(stream, part, ',');) {
    if (!part.empty()) parts.push_back(part);
  }
  return parts;
}

/// The train subcommand's options, written into *args when the command line is parsed.
void addTrainOptions(CLI::App* train, TrainArgs* args) {
  train
      ->add_option("--source", args->source,
                   "as for cblox-capture; sim:yard is the training scene (sim:room|hall|town\n"
                   "are evaluation scenes, refused without --allow-evaluation-scene)")
      ->type_name("SPEC");
  train->add_option("--out", args->out, "the vocabulary file to write")->type_name("FILE");
  train->add_option("--frames", args->frames, "training frames")->capture_default_str();
  train->add_option("--every", args->every, "take every K-th frame of the source")
      ->type_name("K")
      ->capture_default_str();
  train
      ->add_option_function<std::string>(
          "--trajectory",
          [args](const std::string& kinds) { args->trajectories = splitCommas(kinds); },
          "sim: trajectories sharing the frames (default loop,figure-eight,orbit,lawnmower)")
      ->type_name("KIND[,KIND...]");
  train->add_option("--laps", args->laps, "laps of each trajectory")->capture_default_str();
  train->add_option("--noise", args->noise, "none | realistic")->capture_default_str();
  train->add_option("--texture-seed", args->texture_seed, "simulator texture (evaluation: 1)")
      ->type_name("S")
      ->capture_default_str();
  train->add_option("--features", args->features, "ORB features per image")->capture_default_str();
  train->add_option("--k", args->vocabulary.branching, "branching of the vocabulary tree")
      ->capture_default_str();
  train->add_option("--levels", args->vocabulary.levels, "levels of the vocabulary tree")
      ->type_name("L")
      ->capture_default_str();
  train->add_option("--seed", args->vocabulary.seed, "k-majority seed")->capture_default_str();
  train
      ->add_option("--max-iterations", args->vocabulary.max_iterations,
                   "k-majority iterations per split at the most")
      ->capture_default_str();
  train->add_option("--threads", args->vocabulary.num_threads, "training threads")
      ->type_name("T")
      ->capture_default_str();
  train->add_flag("--allow-evaluation-scene", args->allow_evaluation_scene,
                  "allow sim:room|hall|town (experiments only)");
  train->add_flag("--quiet", args->quiet, "no progress lines");
}

/// Checks the train options; throws UsageError.
void checkTrainArgs(const TrainArgs& args) {
  if (args.source.empty()) throw UsageError("train needs --source SPEC (see --help)");
  if (args.out.empty()) throw UsageError("train needs --out FILE (see --help)");
  if (args.frames < 1) throw UsageError("--frames must be >= 1");
  if (args.every < 1) throw UsageError("--every must be >= 1");
  if (args.laps < 1) throw UsageError("--laps must be >= 1");
  if (args.features < 1) throw UsageError("--features must be >= 1");
  if (args.trajectories.empty()) throw UsageError("--trajectory needs at least one kind");
  if (const std::string error = args.vocabulary.validate(); !error.empty()) {
    throw UsageError("vocabulary: " + error);
  }
  for (const char* scene : {"sim:room", "sim:hall", "sim:town"}) {
    if (args.source == scene && !args.allow_evaluation_scene) {
      throw UsageError(args.source +
                       " is an evaluation scene; train on sim:yard (or pass "
                       "--allow-evaluation-scene for experiments)");
    }
  }
}

/// Extracts the descriptors of training images and reports progress.
class Collector {
 public:
  Collector(const TrainArgs& args, Clock::time_point start)
      : args_(args), start_(start), extractor_(extractorConfig(args)) {}

  void add(const GrayImage& image) {
    const auto extract_start = Clock::now();
    images_.push_back(extractor_.extract(image).descriptors);
    extract_seconds_ += secondsSince(extract_start);
    const double elapsed = secondsSince(start_);
    const int done = static_cast<int>(images_.size());
    if (!args_.quiet && (elapsed - last_report_ >= 2.0 || done == args_.frames)) {
      last_report_ = elapsed;
      const double rate = done / std::max(elapsed, 1e-9);
      std::printf("  frames %d/%d  %.1f frames/s  ETA %.0f s\n", done, args_.frames, rate,
                  (args_.frames - done) / rate);
      std::fflush(stdout);
    }
  }

  int count() const { return static_cast<int>(images_.size()); }
  double extractSeconds() const { return extract_seconds_; }
  std::vector<std::vector<OrbDescriptor>>& images() { return images_; }

 private:
  static OrbExtractorConfig extractorConfig(const TrainArgs& args) {
    OrbExtractorConfig config;
    config.num_features = args.features;
    return config;
  }

  const TrainArgs& args_;
  Clock::time_point start_;
  OrbExtractor extractor_;
  std::vector<std::vector<OrbDescriptor>> images_;
  double extract_seconds_ = 0.0;
  double last_report_ = -1e9;
};

/// A built-in simulator scene, played without a SimSource: only the left grey image of every
/// K-th pose of a 20 Hz trajectory is rendered (SimRenderer::renderView) and given the sensor
/// model's image noise and exposure gain, about three times faster than rendering the whole
/// rig (stereo, depth, colour) per frame. Returns the frames taken.
int playBuiltinScene(const TrainArgs& args, const BuiltinScene& scene,
                     const std::shared_ptr<const TriangleMeshRaycaster>& raycaster,
                     const std::string& trajectory, int wanted, Collector* collector) {
  SimRendererConfig config;
  config.rig.depth_max_m = scene.depth_max_m;
  config.texture.base_wavelength_m = scene.texture_wavelength_m;
  config.texture.seed = args.texture_seed;
  const SimRenderer renderer(raycaster, config);
  const SensorModel sensor(sensorNoisePreset(args.noise));
  const double rate_hz = SimSourceConfig{}.rate_hz;
  StampedTrajectory poses;
  try {
    poses = makeSceneTrajectory(scene, parseTrajectoryKind(trajectory), rate_hz, args.laps);
  } catch (const std::invalid_argument& e) {
    throw UsageError(e.what());
  }
  GrayImage image;
  int taken = 0;
  for (size_t i = 0; i < poses.size() && taken < wanted; i += static_cast<size_t>(args.every)) {
    renderer.renderView(poses[i].T_G_C, config.rig.stereo, &image, nullptr, nullptr);
    const auto frame_id = static_cast<int64_t>(i);
    sensor.applyImageNoise(frame_id, 0, sensor.gain(poses[i].timestamp_s), &image);
    collector->add(image);
    ++taken;
  }
  return taken;
}

/// Any other source (datasets, mesh files): every K-th frame's left image. Returns the
/// frames taken.
int playSource(const TrainArgs& args, const std::string& trajectory, int wanted,
               Collector* collector) {
  SourceConfig options;
  options.trajectory = trajectory;
  options.laps = args.laps;
  options.sim.noise = sensorNoisePreset(args.noise);
  options.sim.renderer.texture.seed = args.texture_seed;
  options.max_frames = static_cast<size_t>(wanted) * static_cast<size_t>(args.every);
  std::string error;
  std::unique_ptr<FrameSource> source = openFrameSource(args.source, options, &error);
  if (source == nullptr) throw UsageError(error);
  CaptureFrame frame;
  int taken = 0;
  for (int64_t index = 0; taken < wanted; ++index) {
    const FrameSource::Status status = source->next(&frame, &error);
    if (status == FrameSource::Status::kEnd) break;
    if (status == FrameSource::Status::kError) {
      std::fprintf(stderr, "cblox-vocabulary: skipping a frame: %s\n", error.c_str());
      continue;
    }
    if (index % args.every != 0) continue;
    if (frame.left.empty()) throw std::runtime_error(args.source + " delivers no left image");
    collector->add(frame.left);
    ++taken;
  }
  return taken;
}

/// Creates the output's folder and checks that the file can be written before any work.
void checkWritable(const std::string& path) {
  const std::filesystem::path out(path);
  std::error_code ec;
  if (out.has_parent_path()) std::filesystem::create_directories(out.parent_path(), ec);
  const std::string probe = path + ".tmp";
  if (!std::ofstream(probe, std::ios::binary)) throw UsageError(path + ": cannot write " + probe);
  std::filesystem::remove(probe, ec);
}

int train(const TrainArgs& args) {
  const auto start = Clock::now();
  checkWritable(args.out);
  Collector collector(args, start);
  if (!args.quiet) {
    std::printf("cblox-vocabulary: %d frames (every %d) of %s, %d features each\n", args.frames,
                args.every, args.source.c_str(), args.features);
    std::fflush(stdout);
  }
  // A built-in scene is generated (and its ray-tracing structure built) once for all paths.
  const std::string scene_name = args.source.starts_with("sim:") ? args.source.substr(4) : "";
  const std::vector<std::string> builtin = builtinSceneNames();
  std::optional<BuiltinScene> scene;
  std::shared_ptr<const TriangleMeshRaycaster> raycaster;
  if (std::find(builtin.begin(), builtin.end(), scene_name) != builtin.end()) {
    scene = makeBuiltinScene(scene_name);
    std::string error;
    raycaster = TriangleMeshRaycaster::create(scene->mesh, &error);
    if (raycaster == nullptr) throw std::runtime_error(args.source + ": " + error);
  }
  // The frames are shared equally by the trajectories; a path that ends early leaves its
  // share to the next ones. A dataset is played once.
  const std::vector<std::string> paths =
      args.source.starts_with("sim:") ? args.trajectories : std::vector<std::string>{"-"};
  const int kinds = static_cast<int>(paths.size());
  for (int t = 0; t < kinds; ++t) {
    const int wanted = (args.frames - collector.count()) / (kinds - t);
    const std::string& trajectory = paths[static_cast<size_t>(t)];
    const int taken =
        scene ? playBuiltinScene(args, *scene, raycaster, trajectory, wanted, &collector)
              : playSource(args, trajectory, wanted, &collector);
    if (taken < wanted && !args.quiet) {
      std::printf("  note: %s (%s) ended after %d of %d frames\n", args.source.c_str(),
                  trajectory.c_str(), taken, wanted);
    }
  }
  std::vector<std::vector<OrbDescriptor>>& images = collector.images();
  const double extract_seconds = collector.extractSeconds();
  const double extraction_s = secondsSince(start);
  size_t descriptors = 0;
  for (const auto& image : images) descriptors += image.size();
  if (descriptors == 0) throw std::runtime_error("no ORB feature in any training frame");
  std::ostringstream description;
  description << "ORB (OrbExtractor, " << args.features << " features) of " << images.size()
              << " frames of " << args.source << " (trajectory";
  for (const std::string& t : args.trajectories) description << " " << t;
  description << ", every " << args.every << ", noise " << args.noise << ", texture seed "
              << args.texture_seed << ")";
  if (!args.quiet) {
    std::printf(
        "cblox-vocabulary: %zu descriptors in %.1f s (ORB extraction %.1f s, the rest reading/"
        "rendering); training k = %d, L = %d\n",
        descriptors, extraction_s, extract_seconds, args.vocabulary.branching,
        args.vocabulary.levels);
  }
  BinaryVocabularyTrainingStats stats;
  const BinaryVocabulary vocabulary =
      BinaryVocabulary::train(images, args.vocabulary, description.str(), &stats);
  std::string error;
  if (!vocabulary.save(args.out, &error)) throw UsageError(error);
  std::printf(
      "cblox-vocabulary: %s: %zu words, %zu nodes, k = %d, L = %d, %zu images, %zu descriptors; "
      "%ju bytes; training %.1f s (%zu of %zu splits hit max-iterations), total %.1f s\n",
      args.out.c_str(), stats.words, stats.nodes, args.vocabulary.branching, args.vocabulary.levels,
      stats.images, stats.descriptors, static_cast<uintmax_t>(std::filesystem::file_size(args.out)),
      stats.seconds, stats.unconverged_splits, stats.splits, secondsSince(start));
  return 0;
}

int info(const std::string& path) {
  std::string error;
  const std::optional<BinaryVocabulary> v = BinaryVocabulary::load(path, &error);
  if (!v.has_value()) throw UsageError(error);
  std::vector<size_t> leaves_at_depth(static_cast<size_t>(v->levels()) + 1, 0);
  size_t zero_weight = 0;
  double min_weight = 1e300, max_weight = 0.0, sum_weight = 0.0;
  for (WordId w = 0; w < v->wordCount(); ++w) {
    ++leaves_at_depth[static_cast<size_t>(v->nodeDepth(v->wordNode(w)))];
    const double weight = v->wordWeight(w);
    zero_weight += weight == 0.0;
    min_weight = std::min(min_weight, weight);
    max_weight = std::max(max_weight, weight);
    sum_weight += weight;
  }
  std::printf("%s: %ju bytes\n", path.c_str(),
              static_cast<uintmax_t>(std::filesystem::file_size(path)));
  std::printf("  k = %d, L = %d, %zu nodes, %zu words, %ju training images\n", v->branching(),
              v->levels(), v->nodeCount(), v->wordCount(),
              static_cast<uintmax_t>(v->trainingImageCount()));
  std::printf("  trained on: %s\n", v->description().c_str());
  std::printf("  idf weights: min %.3f, mean %.3f, max %.3f; %zu words with weight 0\n", min_weight,
              sum_weight / static_cast<double>(v->wordCount()), max_weight, zero_weight);
  std::printf("  words per depth:");
  for (size_t d = 1; d < leaves_at_depth.size(); ++d)
    std::printf(" %zu:%zu", d, leaves_at_depth[d]);
  std::printf("\n");
  return 0;
}

}  // namespace
}  // namespace cblox

int main(int argc, char** argv) {
  cblox::TrainArgs train_args;
  std::string info_file;
  CLI::App app{
      "cblox-vocabulary: trains and inspects the binary (ORB) vocabulary of place recognition.\n"
      "Exit status: 0 done, 1 runtime error, 2 usage or file error.",
      "cblox-vocabulary"};
  app.require_subcommand(1);
  CLI::App* train_command = app.add_subcommand(
      "train",
      "extract ORB features from N frames (every K-th frame of the source), train a k-majority\n"
      "vocabulary tree and write it to FILE. The defaults give the build-time vocabulary.");
  cblox::addTrainOptions(train_command, &train_args);
  CLI::App* info_command =
      app.add_subcommand("info", "print a vocabulary file's parameters and statistics");
  info_command->add_option("file", info_file, "the vocabulary")->required()->type_name("FILE");
  if (const std::optional<int> code = cblox::parseCommandLine(app, argc, argv)) return *code;
  try {
    if (train_command->parsed()) {
      cblox::checkTrainArgs(train_args);
      return cblox::train(train_args);
    }
    return cblox::info(info_file);
  } catch (const cblox::UsageError& e) {
    std::fprintf(stderr, "cblox-vocabulary: %s\n", e.what());
    return 2;
  } catch (const cblox::ConfigError& e) {
    std::fprintf(stderr, "cblox-vocabulary: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "cblox-vocabulary: error: %s\n", e.what());
    return 1;
  }
}
