#pragma once

// Test helpers: a fresh temporary directory for one test, and reading a file back.
// Test-only; not thread-safe.

#include <unistd.h>

#include <cctype>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <system_error>

#include <gtest/gtest.h>

namespace cblox::test {

/// A fresh, empty directory under the system's temporary directory ($TMPDIR or /tmp), named
/// "<prefix>_<test suite>_<test name>_<pid>" after the gtest test running when it is created,
/// so that tests and test processes running in parallel never share one (a second TempDir in the
/// same test gets a "-2", "-3", ... suffix). Removed with everything in it on destruction.
/// Not thread-safe.
class TempDir {
 public:
  /// Creates the directory. Throws std::filesystem::filesystem_error if it cannot be created.
  explicit TempDir(const std::string& prefix = "cblox") {
    const std::filesystem::path base = std::filesystem::temp_directory_path() / uniqueName(prefix);
    path_ = base;
    for (int n = 2; !std::filesystem::create_directory(path_); ++n) {
      path_ = base.string() + "-" + std::to_string(n);
    }
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;

  /// The directory.
  const std::filesystem::path& path() const { return path_; }

  /// Path of `name` (may contain '/') inside the directory; the file need not exist.
  std::string file(const std::string& name) const { return (path_ / name).string(); }

  /// Writes `text` verbatim (binary) to file(name), creating missing parent directories, and
  /// returns that path. Adds a gtest failure if the file cannot be written.
  std::string write(const std::string& name, const std::string& text) const {
    const std::string p = file(name);
    std::error_code ec;
    std::filesystem::create_directories(std::filesystem::path(p).parent_path(), ec);
    std::ofstream out(p, std::ios::binary | std::ios::trunc);
    out << text;
    out.close();
    EXPECT_TRUE(out.good()) << "cannot write " << p;
    return p;
  }

 private:
  // "<prefix>_<suite>_<test>_<pid>" with characters other than [A-Za-z0-9_-] replaced by '_'
  // (parameterised tests have '/' in their names).
  static std::string uniqueName(const std::string& prefix) {
    const ::testing::TestInfo* info = ::testing::UnitTest::GetInstance()->current_test_info();
    std::string name = prefix;
    if (info != nullptr) {
      name.append("_").append(info->test_suite_name()).append("_").append(info->name());
    }
    name.append("_").append(std::to_string(::getpid()));
    for (char& c : name) {
      if (!std::isalnum(static_cast<unsigned char>(c)) && c != '_' && c != '-') c = '_';
    }
    return name;
  }

  std::filesystem::path path_;
};

/// The whole content of the file at `path` (read as binary); empty if it cannot be read.
inline std::string readFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

}  // namespace cblox::test
