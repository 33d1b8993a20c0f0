// systemd's notify protocol (Type=notify) on a socket this test owns, as systemd would hold
// it: NOTIFY_SOCKET names an AF_UNIX datagram socket, WATCHDOG_USEC the watchdog interval.
// In-process: the run loop sends READY=1, WATCHDOG=1 every half interval while it turns, no
// ping while a task hangs the loop, STOPPING=1 at the end. Process: the real cblox-mapper
// sends READY=1, STATUS= and periodic WATCHDOG=1, stops pinging while it is stopped, and
// says STOPPING=1 and exits 0 on SIGTERM.

#include <signal.h>
#include <spawn.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "daemon/common/run_loop.h"
#include "daemon/common/systemd_notify.h"

namespace cblox {
namespace {

using Clock = std::chrono::steady_clock;

/// The test's end of NOTIFY_SOCKET: a bound datagram socket in a fresh temporary folder.
class NotifySocket {
 public:
  NotifySocket() {
    char dir_template[] = "/tmp/cblox_notify_XXXXXX";
    dir_ = ::mkdtemp(dir_template);
    path_ = dir_ + "/notify";
    fd_ = ::socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0);
    sockaddr_un addr{};
    addr.sun_family = AF_UNIX;
    std::strncpy(addr.sun_path, path_.c_str(), sizeof(addr.sun_path) - 1);
    EXPECT_EQ(::bind(fd_, reinterpret_cast<sockaddr*>(&addr), sizeof(addr)), 0);
  }
  ~NotifySocket() {
    ::close(fd_);
    ::unlink(path_.c_str());
    ::rmdir(dir_.c_str());
  }
  const std::string& path() const { return path_; }

  struct Message {
    Clock::time_point time;
    std::string text;
  };
  /// Every message that arrives within `timeout`.
  std::vector<Message> receiveFor(std::chrono::milliseconds timeout) {
    std::vector<Message> out;
    const Clock::time_point end = Clock::now() + timeout;
    while (Clock::now() < end) {
      timeval tv{0, 20000};
      ::setsockopt(fd_, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof(tv));
      char buf[4096];
      const ssize_t n = ::recv(fd_, buf, sizeof(buf), 0);
      if (n > 0) out.push_back({Clock::now(), std::string(buf, static_cast<size_t>(n))});
    }
    return out;
  }

 private:
  std::string dir_, path_;
  int fd_ = -1;
};

size_t countWith(const std::vector<NotifySocket::Message>& messages, const std::string& text) {
  size_t n = 0;
  for (const auto& m : messages) n += m.text.find(text) != std::string::npos;
  return n;
}

/// An LCM stand-in for the run loop: handleTimeout just waits.
struct IdleLcm {
  int handleTimeout(int ms) {
    std::this_thread::sleep_for(std::chrono::milliseconds(ms));
    return 0;
  }
};

TEST(SystemdNotify, NothingIsSentOutsideSystemd) {
  ::unsetenv("NOTIFY_SOCKET");
  ::unsetenv("WATCHDOG_USEC");
  SystemdNotifier notifier;
  EXPECT_FALSE(notifier.enabled());
  EXPECT_FALSE(notifier.watchdogEnabled());
  notifier.ready("x");  // no socket: nothing to send, nothing fails
  notifier.pingWatchdogIfDue();
}

TEST(SystemdNotify, RunLoopPingsTheWatchdogOnlyWhileItTurns) {
  NotifySocket socket;
  ::setenv("NOTIFY_SOCKET", socket.path().c_str(), 1);
  ::setenv("WATCHDOG_USEC", "100000", 1);  // 100 ms: a ping every 50 ms
  ::unsetenv("WATCHDOG_PID");
  SystemdNotifier notifier;
  ASSERT_TRUE(notifier.enabled());
  ASSERT_TRUE(notifier.watchdogEnabled());
  EXPECT_EQ(notifier.watchdogInterval(), std::chrono::microseconds(100000));

  // The loop turns for 0.6 s, then a task hangs it for 0.8 s, then it turns 0.6 s more.
  const Clock::time_point start = Clock::now();
  Clock::time_point hang_start, hang_end;
  bool hung = false;
  std::vector<PeriodicTask> tasks{{0.05, 0.0, [&] {
                                     const double t =
                                         std::chrono::duration<double>(Clock::now() - start).count();
                                     if (!hung && t > 0.6) {
                                       hung = true;
                                       hang_start = Clock::now();
                                       std::this_thread::sleep_for(std::chrono::milliseconds(800));
                                       hang_end = Clock::now();
                                     }
                                     if (t > 2.0) g_stop_requested = true;
                                   }}};
  g_stop_requested = false;
  std::vector<NotifySocket::Message> messages;
  std::thread reader([&] { messages = socket.receiveFor(std::chrono::milliseconds(2600)); });
  IdleLcm lcm;
  EXPECT_EQ(serveUntilStopped(lcm, "test", tasks, &notifier), 0);
  reader.join();
  g_stop_requested = false;
  ::unsetenv("NOTIFY_SOCKET");
  ::unsetenv("WATCHDOG_USEC");

  ASSERT_FALSE(messages.empty());
  EXPECT_NE(messages.front().text.find("READY=1"), std::string::npos) << messages.front().text;
  EXPECT_EQ(countWith(messages, "STOPPING=1"), 1u);
  size_t before = 0, during = 0, after = 0;
  for (const auto& m : messages) {
    if (m.text != "WATCHDOG=1") continue;
    if (m.time < hang_start) ++before;
    else if (m.time <= hang_end) ++during;
    else ++after;
  }
  // 0.6 s at a ping per 50-60 ms (the loop turns every 50 ms) before and after the hang.
  EXPECT_GE(before, 6u);
  EXPECT_EQ(during, 0u) << "a hung main loop must not ping the watchdog";
  EXPECT_GE(after, 6u);
}

TEST(SystemdNotify, TheMapperProcessSaysReadyPingsAndStops) {
  NotifySocket socket;
  const std::string out_dir = "/tmp/cblox_notify_mapper_" + std::to_string(::getpid());
  std::vector<std::string> env_strings = {"NOTIFY_SOCKET=" + socket.path(),
                                          "WATCHDOG_USEC=200000", "PATH=/usr/bin:/bin"};
  std::vector<std::string> args = {CBLOX_MAPPER_EXE, "--lcm-url", "memq://", "--output-dir",
                                   out_dir, "--quiet"};
  std::vector<char*> argv, envp;
  for (std::string& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  for (std::string& e : env_strings) envp.push_back(e.data());
  envp.push_back(nullptr);
  pid_t pid = -1;
  ASSERT_EQ(posix_spawn(&pid, argv[0], nullptr, nullptr, argv.data(), envp.data()), 0);

  const auto first = socket.receiveFor(std::chrono::milliseconds(1500));
  ASSERT_FALSE(first.empty()) << "no notification from cblox-mapper";
  EXPECT_NE(first.front().text.find("READY=1"), std::string::npos) << first.front().text;
  EXPECT_GE(countWith(first, "STATUS="), 2u);  // READY's and the status task's
  EXPECT_GE(countWith(first, "WATCHDOG=1"), 5u);  // every 100-150 ms once serving

  ASSERT_EQ(::kill(pid, SIGSTOP), 0);  // the whole process hangs: no pings
  const auto stopped = socket.receiveFor(std::chrono::milliseconds(800));
  EXPECT_EQ(countWith(stopped, "WATCHDOG=1"), 0u);
  ASSERT_EQ(::kill(pid, SIGCONT), 0);
  const auto resumed = socket.receiveFor(std::chrono::milliseconds(800));
  EXPECT_GE(countWith(resumed, "WATCHDOG=1"), 3u);

  ASSERT_EQ(::kill(pid, SIGTERM), 0);
  const auto last = socket.receiveFor(std::chrono::milliseconds(1000));
  EXPECT_EQ(countWith(last, "STOPPING=1"), 1u);
  int status = 0;
  ASSERT_EQ(::waitpid(pid, &status, 0), pid);
  EXPECT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 0);
  std::system(("rm -rf '" + out_dir + "'").c_str());
}

}  // namespace
}  // namespace cblox
