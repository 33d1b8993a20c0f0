// cblox-ctl against a stand-in responder in this process (the real mapper comes later):
// command encoding, matching of the reply by command id, output and exit codes.
// Must run inside a private network namespace (scripts/netns-run.sh; ctest does this).

#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <string>
#include <vector>

#include <cblox/command_reply_t.hpp>
#include <cblox/command_t.hpp>
#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>

#include "test/test_support/read_file.h"

namespace {

struct Responder {
  lcm::LCM* lcm = nullptr;
  bool ok = true;
  bool answer = true;
  std::vector<cblox::command_t> received;
  void onCommand(const lcm::ReceiveBuffer*, const std::string&, const cblox::command_t* cmd) {
    received.push_back(*cmd);
    if (!answer) return;
    cblox::command_reply_t wrong;  // a reply to somebody else's command comes first
    wrong.command_id = cmd->command_id + 1;
    wrong.ok = false;
    wrong.message = "not yours";
    wrong.num_values = 0;
    lcm->publish("CBLOX_CMD_REPLY", &wrong);
    cblox::command_reply_t reply;
    reply.command_id = cmd->command_id;
    reply.ok = ok;
    reply.message = ok ? "wrote out/map.ply" : "path escapes the output directory";
    reply.value_keys = {"vertices"};
    reply.values = {"1234"};
    reply.num_values = 1;
    lcm->publish("CBLOX_CMD_REPLY", &reply);
  }
};

/// Runs cblox-ctl with `args` while answering commands; returns its exit status and output.
int runCtl(Responder* responder, lcm::LCM* lcm, const std::vector<std::string>& args,
           std::string* output) {
  const std::string out_path = "/tmp/cblox_ctl_out_" + std::to_string(::getpid());
  std::vector<std::string> all = {"/bin/sh", "-c", ""};
  std::string cmd = std::string(CBLOX_CTL_EXE);
  for (const std::string& a : args) cmd += " '" + a + "'";
  all[2] = cmd + " > " + out_path + " 2>&1";
  std::vector<char*> argv;
  for (std::string& a : all) argv.push_back(a.data());
  argv.push_back(nullptr);
  pid_t pid = -1;
  EXPECT_EQ(posix_spawn(&pid, argv[0], nullptr, nullptr, argv.data(), nullptr), 0);
  int status = 0;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(30);
  while (std::chrono::steady_clock::now() < deadline) {
    lcm->handleTimeout(50);
    if (waitpid(pid, &status, WNOHANG) == pid) break;
  }
  (void)responder;
  *output = cblox::test::readFile(out_path);
  std::remove(out_path.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

class CtlTest : public testing::Test {
 protected:
  void SetUp() override {
    ASSERT_TRUE(lcm_.good());
    responder_.lcm = &lcm_;
    lcm_.subscribe("CBLOX_CMD", &Responder::onCommand, &responder_);
  }
  lcm::LCM lcm_{"udpm://239.255.76.67:7667?ttl=0"};
  Responder responder_;
};

TEST_F(CtlTest, ExportMeshSendsThePathAndPrintsTheReply) {
  std::string output;
  EXPECT_EQ(runCtl(&responder_, &lcm_, {"export-mesh", "map.ply"}, &output), 0) << output;
  ASSERT_EQ(responder_.received.size(), 1u);
  const cblox::command_t& cmd = responder_.received[0];
  EXPECT_EQ(cmd.name, "export_mesh");
  EXPECT_EQ(cmd.sender, "cblox-ctl");
  ASSERT_EQ(cmd.num_args, 1);
  EXPECT_EQ(cmd.arg_keys[0], "path");
  EXPECT_EQ(cmd.arg_values[0], "map.ply");
  EXPECT_NE(output.find("ok: wrote out/map.ply"), std::string::npos) << output;
  EXPECT_NE(output.find("vertices: 1234"), std::string::npos) << output;
  EXPECT_EQ(output.find("not yours"), std::string::npos) << output;
}

TEST_F(CtlTest, SaveMapAndLoadMapSendThePath) {
  std::string output;
  EXPECT_EQ(runCtl(&responder_, &lcm_, {"save-map", "maps/run1"}, &output), 0) << output;
  EXPECT_EQ(runCtl(&responder_, &lcm_, {"load-map", "/data/maps/run1"}, &output), 0) << output;
  ASSERT_EQ(responder_.received.size(), 2u);
  EXPECT_EQ(responder_.received[0].name, "save_map");
  ASSERT_EQ(responder_.received[0].num_args, 1);
  EXPECT_EQ(responder_.received[0].arg_keys[0], "path");
  EXPECT_EQ(responder_.received[0].arg_values[0], "maps/run1");
  EXPECT_EQ(responder_.received[1].name, "load_map");
  ASSERT_EQ(responder_.received[1].num_args, 1);
  EXPECT_EQ(responder_.received[1].arg_values[0], "/data/maps/run1");
  EXPECT_NE(output.find("vertices: 1234"), std::string::npos) << output;
}

TEST_F(CtlTest, FailureReplyExitsOne) {
  responder_.ok = false;
  std::string output;
  EXPECT_EQ(runCtl(&responder_, &lcm_, {"export-mesh", "../x.ply"}, &output), 1) << output;
  EXPECT_NE(output.find("failed: path escapes"), std::string::npos) << output;
}

TEST_F(CtlTest, NoReplyTimesOutWithStatusThree) {
  responder_.answer = false;
  std::string output;
  EXPECT_EQ(runCtl(&responder_, &lcm_, {"--timeout", "0.5", "status"}, &output), 3) << output;
  EXPECT_NE(output.find("no reply to 'status'"), std::string::npos) << output;
  EXPECT_EQ(responder_.received.size(), 1u);
}

TEST_F(CtlTest, UsageErrorsExitTwo) {
  std::string output;
  EXPECT_EQ(runCtl(&responder_, &lcm_, {"explode"}, &output), 2);
  EXPECT_EQ(runCtl(&responder_, &lcm_, {"export-mesh"}, &output), 2);
  EXPECT_EQ(runCtl(&responder_, &lcm_, {"save-map"}, &output), 2);
  EXPECT_EQ(runCtl(&responder_, &lcm_, {"load-map"}, &output), 2);
  EXPECT_EQ(runCtl(&responder_, &lcm_, {"--timeout", "-1", "status"}, &output), 2);
  EXPECT_TRUE(responder_.received.empty());
}

}  // namespace
