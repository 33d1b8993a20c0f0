// cblox-viewer in a real browser: capture (simulated room) + mapper (ground-truth poses) +
// viewer, and Debian's Chromium headless driven over the DevTools protocol (cdp.py), all in a
// private network namespace (scripts/netns-run.sh; ctest does this). Checks from the page's
// own state (window.cbloxViewer) that every subvolume's mesh blocks arrived, that the mesh
// covers a stated share of the picture (a screenshot is written for people to look at), that
// a keyframe pose correction moves a subvolume's blocks by exactly the correction, and that
// the page reconnects by itself when the viewer restarts and gets the whole map again.

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>
#include <cblox/heartbeat_t.hpp>
#include <cblox/keyframe_pose_batch_t.hpp>
#include <cblox/subvolume_list_t.hpp>
#include <lcm/lcm-cpp.hpp>
#include <nlohmann/json.hpp>

#include "test/test_support/spawn.h"
#include "test/test_support/temp_dir.h"

namespace cblox {
namespace {

using Json = nlohmann::json;
using test::pumpFor;
using test::runTool;

const char* kUrl = "udpm://239.255.76.67:7667?ttl=0&recv_buf_size=4194304";
constexpr int kDevToolsPort = 9222;
const std::string kPage = "http://127.0.0.1:8090/";
// The share of the picture the room's mesh covers, fitted to the view, at least (measured:
// 15 % of 1280 x 657 for this 60-frame orbit, which sees the floor and a few walls).
constexpr double kMinCoverage = 0.10;

// Every subvolume the viewer holds mesh blocks of, and the page holds them all.
const char* kAllBlocksArrived =
    "(() => { const v = window.cbloxViewer; const s = Object.values(v.subvolumes);"
    " return v.connected && v.complete && s.length === 3 && v.blockCount > 0 &&"
    " s.every((x) => x.expected > 0 && x.blocks === x.expected); })()";

struct Received {
  std::optional<subvolume_list_t> subvolumes;
  void onSubvolumes(const lcm::ReceiveBuffer*, const std::string&, const subvolume_list_t* m) {
    subvolumes = *m;
  }
};

class ViewerBrowserTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    if (!std::filesystem::exists("/usr/bin/chromium")) return;  // each test skips
    dir_ = new test::TempDir("viewer_browser");
    lcm_ = new lcm::LCM(kUrl);
    const std::string config = dir_->write(
        "mapper.yaml",
        "subvolumes: {keyframe_every_n_frames: 5, max_keyframes_per_subvolume: 4}\n"
        "mesh_stream: {period_s: 0.5}\n");
    mapper_ = test::spawnProcess({CBLOX_MAPPER_EXE, "--config", config, "--output-dir",
                                  dir_->file("out"), "--lcm-url", kUrl, "--quiet"});
    startViewer();
    chromium_ = test::spawnProcess(
        {"/usr/bin/chromium", "--headless=new", "--no-sandbox", "--use-angle=swiftshader",
         "--enable-unsafe-swiftshader", "--window-size=1280,800", "--hide-scrollbars",
         "--no-first-run", "--log-level=3", "--user-data-dir=" + dir_->file("chromium"),
         "--remote-debugging-port=" + std::to_string(kDevToolsPort), "about:blank"});
    pumpFor(lcm_, std::chrono::milliseconds(1500));
    capture_status_ = runTool(lcm_,
                              {CBLOX_CAPTURE_EXE, "--source", "sim:room", "--trajectory", "orbit",
                               "--frames", "60", "--rate", "10", "--lcm-url", kUrl, "--quiet"},
                              std::chrono::seconds(60));
  }
  static void TearDownTestSuite() {
    for (pid_t* pid : {&chromium_, &viewer_, &mapper_}) {
      if (*pid <= 0) continue;
      kill(*pid, SIGTERM);
      int status = 0;
      for (int i = 0; i < 100 && waitpid(*pid, &status, WNOHANG) == 0; ++i) {
        std::this_thread::sleep_for(std::chrono::milliseconds(100));
      }
      if (waitpid(*pid, &status, WNOHANG) == 0) {
        std::printf("pid %d did not stop within 10 s of SIGTERM: killed\n", *pid);
        kill(*pid, SIGKILL);
        waitpid(*pid, &status, 0);
      }
      *pid = -1;
    }
    delete lcm_;
    delete dir_;
    lcm_ = nullptr;
    dir_ = nullptr;
  }
  void SetUp() override {
    if (!std::filesystem::exists("/usr/bin/chromium")) {
      GTEST_SKIP() << "Debian's chromium is not installed (scripts/setup.sh installs it)";
    }
    ASSERT_EQ(capture_status_, 0);
  }

  static void startViewer(bool allow_export = false) {
    std::vector<std::string> args = {CBLOX_VIEWER_EXE, "--lcm-url", kUrl, "--quiet"};
    if (allow_export) args.push_back("--allow-export");
    viewer_ = test::spawnProcess(args);
  }
  // cdp.py ARGS...: its exit status; its output (stdout and stderr) in *out.
  static int cdp(const std::vector<std::string>& args, std::string* out = nullptr) {
    std::vector<std::string> argv = {"/usr/bin/python3", CBLOX_CDP_PY, "--port",
                                     std::to_string(kDevToolsPort)};
    argv.insert(argv.end(), args.begin(), args.end());
    int fds[2];
    if (pipe(fds) != 0) return -1;
    const pid_t pid = fork();
    if (pid == 0) {
      dup2(fds[1], 1);
      dup2(fds[1], 2);
      close(fds[0]);
      close(fds[1]);
      std::vector<char*> c;
      for (std::string& a : argv) c.push_back(a.data());
      c.push_back(nullptr);
      execv(c[0], c.data());
      _exit(127);
    }
    close(fds[1]);
    std::string text;
    char buffer[4096];
    ssize_t n = 0;
    while ((n = read(fds[0], buffer, sizeof(buffer))) > 0) text.append(buffer, static_cast<size_t>(n));
    close(fds[0]);
    int status = 0;
    waitpid(pid, &status, 0);
    if (out) *out = text;
    const int code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    if (code != 0) std::printf("cdp.py %s: %s\n", args.front().c_str(), text.c_str());
    return code;
  }
  static Json eval(const std::string& expression) {
    std::string out;
    if (cdp({"eval", expression}, &out) != 0) return Json();
    return Json::parse(out, nullptr, false);
  }
  static bool waitFor(const std::string& expression, int seconds) {
    // Keep the LCM socket drained while the browser works.
    return cdp({"--timeout", std::to_string(seconds), "wait", expression}) == 0;
  }

  static inline test::TempDir* dir_ = nullptr;
  static inline lcm::LCM* lcm_ = nullptr;
  static inline pid_t mapper_ = -1, viewer_ = -1, chromium_ = -1;
  static inline int capture_status_ = -1;
};

TEST_F(ViewerBrowserTest, ThePageShowsEverySubvolumesBlocksAndFollowsAPoseCorrection) {
  ASSERT_EQ(cdp({"navigate", kPage}), 0);
  ASSERT_TRUE(waitFor(kAllBlocksArrived, 90)) << eval("JSON.stringify(window.cbloxViewer)");
  const Json blocks = eval("window.cbloxViewer.blockCount");
  std::printf("page: %d mesh blocks in 3 subvolumes\n", blocks.get<int>());

  // The mesh fitted to the view covers a stated share of the picture.
  eval("window.cbloxViewer.fitView()");
  waitFor("new Promise((r) => setTimeout(() => r(true), 500))", 10);
  const Json coverage = eval("window.cbloxViewer.coverage()");
  ASSERT_TRUE(coverage.is_number());
  std::printf("page: the mesh covers %.1f %% of the picture\n", 100.0 * coverage.get<double>());
  EXPECT_GE(coverage.get<double>(), kMinCoverage);
  const std::string shot = std::string(CBLOX_TEST_OUTPUT_DIR) + "/viewer_room.png";
  ASSERT_EQ(cdp({"screenshot", shot}), 0);
  EXPECT_GT(std::filesystem::file_size(shot), 10000u);
  std::printf("screenshot: %s\n", shot.c_str());

  // The health panel hears the mapper and the viewer.
  EXPECT_TRUE(waitFor("'cblox-mapper' in window.cbloxViewer.processes && "
                      "'cblox-viewer' in window.cbloxViewer.processes",
                      10));

  // A pose correction of subvolume 0's anchor keyframe moves its blocks by exactly it.
  Received received;
  lcm::Subscription* sub = lcm_->subscribe("CBLOX_SUBVOLUMES", &Received::onSubvolumes, &received);
  pumpFor(lcm_, std::chrono::milliseconds(1200));
  lcm_->unsubscribe(sub);
  ASSERT_TRUE(received.subvolumes.has_value());
  const subvolume_list_t& list = *received.subvolumes;
  ASSERT_GE(list.num_subvolumes, 1);
  ASSERT_EQ(list.subvolume_ids[0], 0);
  const Json before = eval("window.cbloxViewer.worldBox(0)");
  ASSERT_TRUE(before.is_object());
  keyframe_pose_batch_t batch{};
  batch.utime = 1;
  batch.map_epoch = 0;  // ground-truth keyframes are keys of epoch 0
  batch.reason = keyframe_pose_batch_t::LOOP_CORRECTION;
  batch.num_keyframes = 1;
  batch.keyframe_ids = {list.anchor_keyframe_ids[0]};
  pose_t moved = list.poses[0];
  moved.position[0] += 1.0;
  batch.poses = {moved};
  lcm_->publish("CBLOX_KEYFRAME_POSES", &batch);
  const double x = list.poses[0].position[0];
  ASSERT_TRUE(waitFor("window.cbloxViewer.subvolumes[0].pose[12] > " + std::to_string(x + 0.99),
                      20));
  const Json after = eval("window.cbloxViewer.worldBox(0)");
  ASSERT_TRUE(after.is_object());
  for (const char* corner : {"min", "max"}) {
    EXPECT_NEAR(after[corner][0].get<double>() - before[corner][0].get<double>(), 1.0, 1e-3);
    EXPECT_NEAR(after[corner][1].get<double>(), before[corner][1].get<double>(), 1e-3);
    EXPECT_NEAR(after[corner][2].get<double>(), before[corner][2].get<double>(), 1e-3);
  }
  // The loop closure is an event on the page's timeline.
  EXPECT_TRUE(waitFor("window.cbloxViewer.events.some((e) => e.kind === 'loop')", 5));
}

// What browsers send is bounded and ignored unless it is an allowed export request; more
// browsers than max_clients are refused; both counted in the viewer's heartbeat.
TEST_F(ViewerBrowserTest, BrowserInputIsIgnoredAndCountedAndExtraBrowsersAreRefused) {
  ASSERT_EQ(cdp({"navigate", kPage}), 0);
  ASSERT_TRUE(waitFor(kAllBlocksArrived, 90));
  // From the page: junk, an oversized message, binary bytes and an export request (the
  // viewer is read-only), then five more sockets (max_clients is 4 with the page's).
  const Json opened = eval(
      "new Promise((resolve) => {"
      "  const url = 'ws://' + location.host + '/ws';"
      "  const s = new WebSocket(url);"
      "  s.onopen = () => {"
      "    s.send('not json'); s.send('x'.repeat(100000)); s.send(new Uint8Array([1, 2, 3]));"
      "    s.send(JSON.stringify({type: 'export'}));"
      "    const more = []; let settled = 0;"
      "    for (let i = 0; i < 5; ++i) more.push(new WebSocket(url));"
      "    setTimeout(() => resolve(more.filter((x) => x.readyState === 1).length), 3000);"
      "  };"
      "})");
  ASSERT_TRUE(opened.is_number()) << opened.dump();
  EXPECT_EQ(opened.get<int>(), 2);  // the page's, the junk sender's and 2 of the 5
  // The viewer's heartbeat counts them and it still serves the page.
  struct Heard {
    std::optional<heartbeat_t> viewer;
    void on(const lcm::ReceiveBuffer*, const std::string&, const heartbeat_t* m) {
      if (m->process == "cblox-viewer") viewer = *m;
    }
  } heard;
  lcm::Subscription* sub = lcm_->subscribe("CBLOX_HEARTBEAT", &Heard::on, &heard);
  const auto counter = [&](const std::string& name) -> int64_t {
    for (size_t i = 0; i < heard.viewer->counter_names.size(); ++i) {
      if (heard.viewer->counter_names[i] == name) return heard.viewer->counter_values[i];
    }
    return -1;
  };
  for (int i = 0; i < 20 && !(heard.viewer && counter("clients_refused") >= 3); ++i) {
    pumpFor(lcm_, std::chrono::milliseconds(500));
  }
  lcm_->unsubscribe(sub);
  ASSERT_TRUE(heard.viewer.has_value());
  EXPECT_EQ(counter("browser_messages_ignored"), 4);
  EXPECT_EQ(counter("clients_refused"), 3);
  EXPECT_EQ(counter("export_requests"), 0);
  EXPECT_TRUE(waitFor("window.cbloxViewer.connected", 5));
}

TEST_F(ViewerBrowserTest, ThePageReconnectsWhenTheViewerRestarts) {
  ASSERT_EQ(cdp({"navigate", kPage}), 0);
  ASSERT_TRUE(waitFor(kAllBlocksArrived, 90));
  const Json connections = eval("window.cbloxViewer.connections");
  ASSERT_TRUE(connections.is_number());
  const Json blocks = eval("window.cbloxViewer.blockCount");

  kill(viewer_, SIGTERM);
  int status = 0;
  ASSERT_EQ(waitpid(viewer_, &status, 0), viewer_);
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0);
  ASSERT_TRUE(waitFor("!window.cbloxViewer.connected", 20));
  startViewer(/*allow_export=*/true);
  // The new viewer asks the mapper for a refresh; the page reconnects and gets it all.
  ASSERT_TRUE(waitFor("window.cbloxViewer.connections > " + connections.dump(), 30));
  ASSERT_TRUE(waitFor(kAllBlocksArrived, 60));
  EXPECT_EQ(eval("window.cbloxViewer.blockCount"), blocks);

  // This viewer allows exports: the page's button asks the mapper and offers the PLY.
  ASSERT_TRUE(waitFor("!document.getElementById('export').hidden", 10));
  eval("document.getElementById('export').click()");
  ASSERT_TRUE(waitFor("window.cbloxViewer.lastExport && window.cbloxViewer.lastExport.ok", 60));
  const Json head = eval(
      "fetch(window.cbloxViewer.lastExport.url).then((r) => r.arrayBuffer()).then((b) =>"
      " [b.byteLength, new TextDecoder().decode(new Uint8Array(b, 0, 3))])");
  ASSERT_TRUE(head.is_array()) << head.dump();
  EXPECT_GT(head[0].get<int>(), 10000);
  EXPECT_EQ(head[1], "ply");
}

}  // namespace
}  // namespace cblox
