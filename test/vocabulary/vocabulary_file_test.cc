#include <cstring>
#include <filesystem>
#include <fstream>

#include <unistd.h>

#include <gtest/gtest.h>

#include "core/vocabulary/binary_vocabulary.h"
#include "test/vocabulary/synthetic_descriptors.h"

namespace cblox {
namespace {

class VocabularyFileTest : public ::testing::Test {
 protected:
  VocabularyFileTest()
      : dir_(std::filesystem::temp_directory_path() /
             ("cblox_vocabulary_file_test_" + std::to_string(::getpid()))),
        data_(test::makeClusteredData(30, 12, 15, 3)),
        v_(train()) {
    std::filesystem::create_directories(dir_);
  }
  ~VocabularyFileTest() override { std::filesystem::remove_all(dir_); }

  BinaryVocabulary train() const {
    std::vector<std::vector<OrbDescriptor>> images(6);
    for (size_t i = 0; i < data_.members.size(); ++i) images[i % 6].push_back(data_.members[i]);
    BinaryVocabularyConfig config;
    config.branching = 5;
    config.levels = 3;
    return BinaryVocabulary::train(images, config, "file test");
  }

  std::string path(const std::string& name) const { return (dir_ / name).string(); }

  void write(const std::string& name, const std::string& bytes) const {
    std::ofstream out(path(name), std::ios::binary);
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  }

  /// Loads bytes written to a file; expects failure with a message containing `expected`.
  void expectRejected(const std::string& bytes, const std::string& expected) const {
    write("bad.vocab", bytes);
    std::string error;
    EXPECT_FALSE(BinaryVocabulary::load(path("bad.vocab"), &error).has_value()) << expected;
    EXPECT_NE(error.find(expected), std::string::npos) << "got: " << error;
    EXPECT_EQ(error.rfind(path("bad.vocab"), 0), 0u) << "message names the file: " << error;
  }

  /// Recomputes the trailing FNV-1a checksum after an edit.
  static void fixChecksum(std::string* bytes) {
    uint64_t hash = 0xcbf29ce484222325ull;
    for (size_t i = 0; i + 8 < bytes->size(); ++i) {
      hash ^= static_cast<uint8_t>((*bytes)[i]);
      hash *= 0x100000001b3ull;
    }
    std::memcpy(bytes->data() + bytes->size() - 8, &hash, 8);
  }

  std::filesystem::path dir_;
  test::ClusteredData data_;
  BinaryVocabulary v_;
};

TEST_F(VocabularyFileTest, RoundTripGivesTheSameWordsAndBytes) {
  std::string error;
  ASSERT_TRUE(v_.save(path("v.vocab"), &error)) << error;
  EXPECT_FALSE(std::filesystem::exists(path("v.vocab.tmp")));
  const std::optional<BinaryVocabulary> loaded = BinaryVocabulary::load(path("v.vocab"), &error);
  ASSERT_TRUE(loaded.has_value()) << error;
  EXPECT_EQ(loaded->serialize(), v_.serialize());
  EXPECT_EQ(std::filesystem::file_size(path("v.vocab")), v_.serialize().size());
  EXPECT_EQ(loaded->branching(), 5);
  EXPECT_EQ(loaded->levels(), 3);
  EXPECT_EQ(loaded->nodeCount(), v_.nodeCount());
  EXPECT_EQ(loaded->wordCount(), v_.wordCount());
  EXPECT_EQ(loaded->trainingImageCount(), 6u);
  EXPECT_EQ(loaded->description(), "file test");
  for (const OrbDescriptor& d : data_.members) ASSERT_EQ(loaded->wordOf(d), v_.wordOf(d));
  std::mt19937_64 rng(99);
  std::vector<OrbDescriptor> fresh;  // descriptors never seen in training
  for (int i = 0; i < 200; ++i) fresh.push_back(test::randomDescriptor(rng));
  for (const OrbDescriptor& d : fresh) ASSERT_EQ(loaded->wordOf(d), v_.wordOf(d));
  FeatureVector fa, fb;
  BowVector ba, bb;
  v_.transform(fresh, &ba, &fa);
  loaded->transform(fresh, &bb, &fb);
  EXPECT_EQ(ba, bb);
  EXPECT_EQ(fa, fb);
}

TEST_F(VocabularyFileTest, CorruptAndTruncatedFilesAreRejectedWithTheReason) {
  const std::string good = v_.serialize();
  // Header (40) + description (9) + nodes (36 each) + weights (8 each) + checksum (8).
  EXPECT_EQ(good.size(), 40 + 9 + 36 * (v_.nodeCount() - 1) + 8 * v_.wordCount() + 8);

  std::string wrong_magic = good;
  wrong_magic[0] = 'X';
  expectRejected(wrong_magic, "wrong magic");
  expectRejected("PK\x03\x04 a zip file", "wrong magic");
  expectRejected("", "truncated file");
  expectRejected(good.substr(0, 6), "truncated file");
  expectRejected(good.substr(0, 30), "truncated file");
  expectRejected(good.substr(0, good.size() / 2), "truncated file");
  expectRejected(good.substr(0, good.size() - 1), "truncated file");
  expectRejected(good + "x", "bytes after the end");

  std::string flipped = good;
  flipped[good.size() / 2] ^= 0x10;  // a bit of some node
  expectRejected(flipped, "checksum mismatch");

  std::string version = good;
  version[8] = 2;
  expectRejected(version, "unsupported format version 2");

  std::string bad_k = good;
  bad_k[12] = 1;
  expectRejected(bad_k, "corrupt header");

  // A valid checksum over an inconsistent tree: node 1's parent points forward.
  std::string forward = good;
  const uint32_t parent = 5;
  std::memcpy(forward.data() + 40 + 9, &parent, 4);
  fixChecksum(&forward);
  expectRejected(forward, "inconsistent tree");

  std::string error;
  EXPECT_FALSE(BinaryVocabulary::load(path("missing.vocab"), &error).has_value());
  EXPECT_NE(error.find("cannot open"), std::string::npos) << error;
  EXPECT_FALSE(v_.save((dir_ / "no_such_dir" / "v.vocab").string(), &error));
  EXPECT_NE(error.find("cannot write"), std::string::npos) << error;
}

}  // namespace
}  // namespace cblox
