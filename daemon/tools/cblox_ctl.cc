// cblox-ctl: sends one command to the mapper over LCM and prints its reply.
//
//   cblox-ctl status
//   cblox-ctl export-mesh map.ply
//   cblox-ctl export-submap-meshes submaps/
//   cblox-ctl --timeout 30 --lcm-url "udpm://239.255.76.67:7667?ttl=0" export-mesh map.ply
//
// Paths are relative to the mapper's configured output directory (the mapper rejects
// absolute paths outside it and any "..").
// Exit status: 0 the command succeeded, 1 the mapper answered with a failure, 2 usage
// error, 3 no reply within the timeout (is cblox-mapper running, on the same LCM URL?).

#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <cblox/command_reply_t.hpp>
#include <cblox/command_t.hpp>
#include <lcm/lcm-cpp.hpp>

namespace {

using Clock = std::chrono::steady_clock;

void printUsage(std::FILE* out) {
  std::fprintf(out,
               "usage: cblox-ctl [--lcm-url URL] [--timeout SECONDS] [--channel CBLOX_CMD]\n"
               "                 [--reply-channel CBLOX_CMD_REPLY] COMMAND [ARG]\n"
               "commands:\n"
               "  status                      print the mapper's statistics\n"
               "  export-mesh PATH            write the global mesh (PLY) to PATH\n"
               "  export-submap-meshes DIR    write one mesh per subvolume, coloured by subvolume\n"
               "exit status: 0 ok, 1 the mapper reported a failure, 2 usage, 3 no reply\n");
}

struct Reply {
  std::optional<cblox::command_reply_t> reply;
  int64_t expected_id = 0;
  void onReply(const lcm::ReceiveBuffer*, const std::string&, const cblox::command_reply_t* msg) {
    if (msg->command_id == expected_id) reply = *msg;
  }
};

int64_t nowUtime() {
  return std::chrono::duration_cast<std::chrono::microseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

}  // namespace

int main(int argc, char** argv) {
  std::string url, channel = "CBLOX_CMD", reply_channel = "CBLOX_CMD_REPLY";
  double timeout_s = 10.0;
  std::vector<std::string> positional;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) {
        std::fprintf(stderr, "cblox-ctl: %s needs a value\n", arg.c_str());
        std::exit(2);
      }
      return argv[++i];
    };
    if (arg == "--help" || arg == "-h") {
      printUsage(stdout);
      return 0;
    } else if (arg == "--lcm-url") {
      url = value();
    } else if (arg == "--timeout") {
      const std::string text = value();
      char* end = nullptr;
      timeout_s = std::strtod(text.c_str(), &end);
      if (end == text.c_str() || *end != '\0' || !(timeout_s > 0.0)) {
        std::fprintf(stderr, "cblox-ctl: --timeout needs seconds > 0, got '%s'\n", text.c_str());
        return 2;
      }
    } else if (arg == "--channel") {
      channel = value();
    } else if (arg == "--reply-channel") {
      reply_channel = value();
    } else if (arg.rfind("--", 0) == 0) {
      std::fprintf(stderr, "cblox-ctl: unknown option '%s'\n", arg.c_str());
      printUsage(stderr);
      return 2;
    } else {
      positional.push_back(arg);
    }
  }
  if (positional.empty()) {
    printUsage(stderr);
    return 2;
  }
  cblox::command_t command;
  const std::string& verb = positional[0];
  if (verb == "status" && positional.size() == 1) {
    command.name = "status";
  } else if (verb == "export-mesh" && positional.size() == 2) {
    command.name = "export_mesh";
    command.arg_keys = {"path"};
    command.arg_values = {positional[1]};
  } else if (verb == "export-submap-meshes" && positional.size() == 2) {
    command.name = "export_submap_meshes";
    command.arg_keys = {"path"};
    command.arg_values = {positional[1]};
  } else {
    std::fprintf(stderr, "cblox-ctl: unknown command or wrong arguments: '%s'\n", verb.c_str());
    printUsage(stderr);
    return 2;
  }
  command.num_args = static_cast<int32_t>(command.arg_keys.size());
  command.utime = nowUtime();
  command.command_id = (static_cast<int64_t>(::getpid()) << 32) ^ (command.utime & 0xFFFFFFFF);
  command.sender = "cblox-ctl";

  lcm::LCM lcm(url);
  if (!lcm.good()) {
    std::fprintf(stderr, "cblox-ctl: cannot open LCM (url '%s')\n", url.c_str());
    return 2;
  }
  Reply reply;
  reply.expected_id = command.command_id;
  lcm.subscribe(reply_channel, &Reply::onReply, &reply);
  if (lcm.publish(channel, &command) != 0) {
    std::fprintf(stderr, "cblox-ctl: cannot publish on %s\n", channel.c_str());
    return 2;
  }
  const auto deadline =
      Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(timeout_s));
  while (!reply.reply && Clock::now() < deadline) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now());
    if (lcm.handleTimeout(static_cast<int>(std::max<int64_t>(1, std::min<int64_t>(left.count(), 200)))) < 0) {
      std::fprintf(stderr, "cblox-ctl: LCM receive failed\n");
      return 2;
    }
  }
  if (!reply.reply) {
    std::fprintf(stderr,
                 "cblox-ctl: no reply to '%s' on %s within %.1f s (is cblox-mapper running on "
                 "the same LCM URL?)\n",
                 command.name.c_str(), reply_channel.c_str(), timeout_s);
    return 3;
  }
  const cblox::command_reply_t& r = *reply.reply;
  std::printf("%s: %s\n", r.ok ? "ok" : "failed", r.message.c_str());
  for (int32_t i = 0; i < r.num_values && i < static_cast<int32_t>(r.values.size()); ++i) {
    std::printf("  %s: %s\n", r.value_keys[i].c_str(), r.values[i].c_str());
  }
  return r.ok ? 0 : 1;
}
