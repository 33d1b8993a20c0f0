#include "core/io/atomic_file.h"

#include <signal.h>
#include <sys/resource.h>

#include <algorithm>
#include <filesystem>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "test/test_support/temp_dir.h"

namespace cblox {
namespace {

namespace fs = std::filesystem;

// Names of the entries of `dir`, to check that no temporary file is left behind.
std::vector<std::string> entries(const fs::path& dir) {
  std::vector<std::string> names;
  for (const fs::directory_entry& e : fs::directory_iterator(dir)) {
    names.push_back(e.path().filename().string());
  }
  std::sort(names.begin(), names.end());
  return names;
}

TEST(AtomicFile, WritesAndReplacesWithoutLeavingTemporaries) {
  test::TempDir dir("cblox_atomic");
  const std::string path = dir.file("a.bin");
  std::string error;
  ASSERT_TRUE(writeFileAtomically(path, std::string("first\0x", 7), &error)) << error;
  EXPECT_EQ(test::readFile(path), std::string("first\0x", 7));
  ASSERT_TRUE(writeFileAtomically(path, "second", &error)) << error;
  EXPECT_EQ(test::readFile(path), "second");
  ASSERT_TRUE(writeFileAtomically(path, "", &error)) << error;
  EXPECT_EQ(test::readFile(path), "");
  EXPECT_EQ(entries(dir.path()), (std::vector<std::string>{"a.bin"}));
  EXPECT_TRUE(syncDirectory(dir.path().string(), &error)) << error;
}

TEST(AtomicFile, ErrorsNameThePathAndTheReason) {
  test::TempDir dir("cblox_atomic");
  const std::string path = dir.file("missing/a.bin");
  std::string error;
  EXPECT_FALSE(writeFileAtomically(path, "x", &error));
  EXPECT_NE(error.find(path), std::string::npos) << error;
  EXPECT_NE(error.find("No such file or directory"), std::string::npos) << error;
  EXPECT_FALSE(syncDirectory(dir.file("missing"), &error));
  EXPECT_NE(error.find(dir.file("missing")), std::string::npos) << error;

  // The target is a non-empty directory: the rename fails, the temporary file is removed.
  dir.write("d/inside", "keep");
  EXPECT_FALSE(writeFileAtomically(dir.file("d"), "x", &error));
  EXPECT_NE(error.find("rename failed"), std::string::npos) << error;
  EXPECT_EQ(test::readFile(dir.file("d/inside")), "keep");
  EXPECT_EQ(entries(dir.path()), (std::vector<std::string>{"d"}));
}

// A write that fails half-way (the file size limit, as on a full disk) leaves the old file
// complete and removes the temporary file.
TEST(AtomicFile, FailedWriteKeepsTheOldFile) {
  test::TempDir dir("cblox_atomic");
  const std::string path = dir.file("map.bin");
  ASSERT_TRUE(writeFileAtomically(path, "old content", nullptr));

  struct sigaction ignore {
  }, old_action{};
  ignore.sa_handler = SIG_IGN;
  ASSERT_EQ(sigaction(SIGXFSZ, &ignore, &old_action), 0);
  rlimit old_limit{};
  ASSERT_EQ(getrlimit(RLIMIT_FSIZE, &old_limit), 0);
  rlimit limit = old_limit;
  limit.rlim_cur = 4096;
  ASSERT_EQ(setrlimit(RLIMIT_FSIZE, &limit), 0);
  std::string error;
  const bool written = writeFileAtomically(path, std::string(100000, 'n'), &error);
  setrlimit(RLIMIT_FSIZE, &old_limit);
  sigaction(SIGXFSZ, &old_action, nullptr);

  EXPECT_FALSE(written);
  EXPECT_NE(error.find(path + ": write failed: File too large"), std::string::npos) << error;
  EXPECT_EQ(test::readFile(path), "old content");
  EXPECT_EQ(entries(dir.path()), (std::vector<std::string>{"map.bin"}));
}

}  // namespace
}  // namespace cblox
