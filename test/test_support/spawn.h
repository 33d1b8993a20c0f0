#pragma once

#include <signal.h>
#include <spawn.h>
#include <sys/types.h>
#include <sys/wait.h>

#include <chrono>
#include <optional>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>

extern char** environ;

namespace cblox::test {

// Starting the processes of the multi-process tests, and waiting for them while this
// process handles LCM (they talk to it meanwhile).

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

/// Handles `lcm` until `pid` exits or the deadline passes; its exit status (128 + signal when
/// killed by one), or nullopt at the deadline.
inline std::optional<int> waitWhilePumping(lcm::LCM* lcm, pid_t pid,
                                           std::chrono::steady_clock::time_point deadline) {
  int status = 0;
  while (std::chrono::steady_clock::now() < deadline) {
    lcm->handleTimeout(50);
    if (waitpid(pid, &status, WNOHANG) == pid) {
      return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
    }
  }
  return std::nullopt;
}

/// Handles `lcm` for `duration`.
inline void pumpFor(lcm::LCM* lcm, std::chrono::milliseconds duration) {
  const auto until = std::chrono::steady_clock::now() + duration;
  while (std::chrono::steady_clock::now() < until) lcm->handleTimeout(20);
}

/// Runs a tool to completion while handling `lcm`; its exit status, or -1 when it did not
/// end within `timeout` (then it is killed).
inline int runTool(lcm::LCM* lcm, const std::vector<std::string>& args,
                   std::chrono::seconds timeout) {
  const pid_t pid = spawnProcess(args);
  if (pid <= 0) return -1;
  const std::optional<int> status =
      waitWhilePumping(lcm, pid, std::chrono::steady_clock::now() + timeout);
  if (!status) {
    kill(pid, SIGKILL);
    waitpid(pid, nullptr, 0);
    return -1;
  }
  return *status;
}

/// Sends SIGTERM to `pid` and handles `lcm` until it exits: its exit status, or nullopt when
/// it did not exit within `timeout` (then it is killed with SIGKILL and reaped).
inline std::optional<int> terminateWhilePumping(lcm::LCM* lcm, pid_t pid,
                                                std::chrono::seconds timeout) {
  if (kill(pid, SIGTERM) != 0) return std::nullopt;
  const std::optional<int> status =
      waitWhilePumping(lcm, pid, std::chrono::steady_clock::now() + timeout);
  if (!status) {
    kill(pid, SIGKILL);
    waitpid(pid, nullptr, 0);
  }
  return status;
}

}  // namespace cblox::test
