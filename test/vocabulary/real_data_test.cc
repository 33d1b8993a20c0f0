// The build-time vocabulary (trained on simulator images of sim:yard only) on real images:
// EuRoC V1_01 stereo pairs (same place, 11 cm apart, two sensors) against 7-Scenes frames
// (another place and camera). Skips without ../shared/data or the build-time vocabulary.

#include <algorithm>
#include <filesystem>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include "core/features/orb_extractor.h"
#include "core/vocabulary/binary_vocabulary.h"
#include "test/vocabulary/build_time_vocabulary.h"

namespace cblox {
namespace {

/// BoW vectors of the first `count` images (sorted by name) in `dir` ending in `suffix`.
std::vector<BowVector> readBows(const BinaryVocabulary& v, const std::filesystem::path& dir,
                                const std::string& suffix, size_t count) {
  std::vector<std::string> files;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    const std::string name = entry.path().string();
    if (name.ends_with(suffix)) files.push_back(name);
  }
  std::sort(files.begin(), files.end());
  files.resize(std::min(files.size(), count));
  OrbExtractor extractor(OrbExtractorConfig{});
  std::vector<BowVector> bows;
  for (const std::string& file : files) {
    const cv::Mat image = cv::imread(file, cv::IMREAD_GRAYSCALE);
    if (image.empty()) ADD_FAILURE() << "cannot read " << file;
    if (!image.empty()) bows.push_back(v.transform(extractor.extract(image).descriptors));
  }
  return bows;
}

TEST(RealDataTest, SimulatorTrainedVocabularyRecognisesARealStereoPairAmongOtherPlaces) {
  const std::filesystem::path data(CBLOX_SHARED_DATA_DIR);
  const std::filesystem::path euroc = data / "euroc-v101-micro" / "mav0";
  const std::filesystem::path seven = data / "7scenes-rgbd-50";
  if (!std::filesystem::exists(euroc) || !std::filesystem::exists(seven)) {
    GTEST_SKIP() << "no ../shared/data (EuRoC and 7-Scenes frames)";
  }
  const test::BuildTimeVocabulary built = test::loadBuildTimeVocabulary();
  if (!built.skip_reason.empty()) GTEST_SKIP() << built.skip_reason;
  ASSERT_TRUE(built.vocabulary.has_value()) << built.error;
  const BinaryVocabulary& v = *built.vocabulary;
  const std::vector<BowVector> left = readBows(v, euroc / "cam0" / "data", ".png", 8);
  const std::vector<BowVector> right = readBows(v, euroc / "cam1" / "data", ".png", 8);
  const std::vector<BowVector> other = readBows(v, seven, ".color.png", 8);
  ASSERT_EQ(left.size(), 8u);
  ASSERT_EQ(right.size(), 8u);
  ASSERT_EQ(other.size(), 8u);
  double min_pair = 1.0, max_cross = 0.0, mean_pair = 0.0, mean_cross = 0.0;
  for (size_t i = 0; i < left.size(); ++i) {
    const double s = BinaryVocabulary::score(left[i], right[i]);
    min_pair = std::min(min_pair, s);
    mean_pair += s / 8.0;
    for (const BowVector& o : other) {
      for (const BowVector* e : {&left[i], &right[i]}) {
        const double c = BinaryVocabulary::score(*e, o);
        max_cross = std::max(max_cross, c);
        mean_cross += c / 128.0;
      }
    }
  }
  std::printf(
      "[ build-time vocabulary on real images ] EuRoC left-right score min %.4f mean %.4f; "
      "EuRoC vs 7-Scenes max %.4f mean %.4f\n",
      min_pair, mean_pair, max_cross, mean_cross);
  EXPECT_GT(min_pair, max_cross);
  EXPECT_GT(mean_pair, 2.5 * mean_cross);
}

}  // namespace
}  // namespace cblox
