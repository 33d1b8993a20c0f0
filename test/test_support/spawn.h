#pragma once

#include <spawn.h>
#include <sys/types.h>

#include <string>
#include <vector>

#include <gtest/gtest.h>

extern char** environ;

namespace cblox::test {

/// Starts args[0] (a path) with the arguments and this process's environment; returns its
/// pid (-1, with a test failure, if it cannot be started). For the multi-process tests.
inline pid_t spawnProcess(const std::vector<std::string>& args) {
  std::vector<char*> argv;
  for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  pid_t pid = -1;
  EXPECT_EQ(posix_spawn(&pid, argv[0], nullptr, nullptr, argv.data(), environ), 0) << args[0];
  return pid;
}

}  // namespace cblox::test
