// cblox-map-verify as operators and scripts/crash_test.sh run it: a valid map (exit 0, its
// generation and submaps, the loaded voxels re-encoded to the files' XXH64), a corrupt or
// incomplete one (exit 1, the file named), --manifest-only, and usage errors (exit 2).

#include <sys/wait.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "core/io/atomic_file.h"
#include "core/persistence/map_store.h"
#include "test/persistence/map_test_collection.h"
#include "test/test_support/temp_dir.h"

namespace cblox {
namespace {

// Runs the tool with `args`; its exit status, stdout in *out and stderr in *err.
int runTool(const std::string& args, std::string* out, std::string* err) {
  test::TempDir capture("cblox_map_verify_out");
  const std::string o = (capture.path() / "out").string(), e = (capture.path() / "err").string();
  const int status = std::system(
      (std::string(CBLOX_MAP_VERIFY_EXE) + " " + args + " > " + o + " 2> " + e).c_str());
  *out = test::readFile(o);
  *err = test::readFile(e);
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

class MapVerifyTool : public ::testing::Test {
 protected:
  void SetUp() override {
    std::string error;
    manifest_ = saveMap(*collection_, dir_.path().string(), {{"frames_integrated", 3}}, {}, nullptr,
                        &error);
    ASSERT_TRUE(manifest_) << error;
  }
  std::unique_ptr<SubmapCollection> collection_ = test::buildTestCollection();
  test::TempDir dir_{"cblox_map_verify"};
  std::optional<MapManifest> manifest_;
};

TEST_F(MapVerifyTool, AValidMapIsListedAndItsLoadedVoxelsMatchTheFiles) {
  std::string out, err;
  ASSERT_EQ(runTool(dir_.path().string() + " --json", &out, &err), 0) << err;
  const nlohmann::json m = nlohmann::json::parse(out);
  EXPECT_TRUE(m["ok"].get<bool>());
  EXPECT_EQ(m["generation"].get<uint64_t>(), manifest_->generation);
  EXPECT_EQ(m["counters"]["frames_integrated"].get<int64_t>(), 3);
  ASSERT_EQ(m["submaps"].size(), manifest_->submaps.size());
  for (size_t i = 0; i < manifest_->submaps.size(); ++i) {
    const nlohmann::json& s = m["submaps"][i];
    const SubmapRecord& r = manifest_->submaps[i];
    EXPECT_EQ(s["id"].get<int64_t>(), r.id);
    EXPECT_EQ(s["file"].get<std::string>(), r.file.file_name);
    EXPECT_EQ(s["blocks"].get<uint64_t>(), r.file.num_blocks);
    EXPECT_EQ(s["keyframes"].get<std::vector<int64_t>>(), r.keyframe_ids);
    EXPECT_EQ(std::stoull(s["xxh64"].get<std::string>(), nullptr, 16), r.file.payload_xxh64);
    EXPECT_EQ(s["loaded_xxh64"], s["xxh64"]);
  }
  ASSERT_EQ(runTool(dir_.path().string(), &out, &err), 0) << err;
  EXPECT_NE(out.find("generation " + std::to_string(manifest_->generation) + ", " +
                     std::to_string(manifest_->submaps.size()) + " submaps"),
            std::string::npos)
      << out;
  EXPECT_NE(out.find(manifest_->submaps[0].file.file_name), std::string::npos) << out;
}

TEST_F(MapVerifyTool, ACorruptOrMissingFileIsAProblemNamingIt) {
  const std::string name = manifest_->submaps[1].file.file_name;
  const std::string path = dir_.file(name);
  std::string bytes = test::readFile(path);
  bytes[bytes.size() / 2] ^= 0x01;
  ASSERT_TRUE(writeFileAtomically(path, bytes, nullptr));
  dir_.write("submap_1_g99.cbsub", "left by an interrupted checkpoint");
  std::string out, err;
  EXPECT_EQ(runTool(dir_.path().string() + " --json", &out, &err), 1);
  EXPECT_NE(err.find(path + ": checksum mismatch"), std::string::npos) << err;
  const nlohmann::json m = nlohmann::json::parse(out);
  EXPECT_FALSE(m["ok"].get<bool>());
  EXPECT_EQ(m["unlisted_files"], nlohmann::json::array({"submap_1_g99.cbsub"}));
  // The manifest alone is fine.
  EXPECT_EQ(runTool(dir_.path().string() + " --manifest-only", &out, &err), 0) << err;
  std::filesystem::remove(dir_.file(kManifestFileName));
  EXPECT_EQ(runTool(dir_.path().string() + " --manifest-only", &out, &err), 1);
  EXPECT_NE(err.find("cannot open map manifest"), std::string::npos) << err;
}

TEST_F(MapVerifyTool, UsageErrorsExitTwo) {
  std::string out, err;
  EXPECT_EQ(runTool("", &out, &err), 2);
  EXPECT_EQ(runTool(dir_.path().string() + " --no-such-flag", &out, &err), 2);
}

}  // namespace
}  // namespace cblox
