// cblox-ctl: sends one command to the mapper over LCM and prints its reply, or summarises the
// health of every cblox process from their heartbeats.
//
//   cblox-ctl status
//   cblox-ctl export-mesh map.ply
//   cblox-ctl export-submap-meshes submaps/
//   cblox-ctl save-map maps/run1                 # a map directory (README, "Map file format")
//   cblox-ctl load-map /data/maps/run1           # into a mapper whose map is still empty
//   cblox-ctl --timeout 30 --lcm-url "udpm://239.255.76.67:7667?ttl=0" export-mesh map.ply
//   cblox-ctl status --all                      # every process: pid, state, rates, CPU, ...
//   cblox-ctl status --all --listen 3 --expect tracker,mapper
//   cblox-ctl distance 1.0 0.5 1.2 [X Y Z ...]   # the planning map at points of G
//   cblox-ctl grid --box -2,-2,0,2,2,2 --resolution 0.1 --out grid.ply
//   cblox-ctl esdf-slice --z 1.0 --out slice.png
//
// Paths are relative to the mapper's configured output directory (the mapper rejects
// absolute paths outside it and any ".."); load-map's is any map directory the mapper can read.
// `status --all` listens to CBLOX_HEARTBEAT and CBLOX_MAP_STATUS for --listen seconds (1.5)
// and prints one row per process heard (and per expected process not heard), then the map.
// Every message is decoded through the wire check (lcmtypes/wire_check.h): a malformed
// message is counted and ignored, never trusted.
// `distance` sends one distance_request_t on CBLOX_DISTANCE_REQUEST and prints the
// distance_reply_t: per point its state (free / occupied / unknown), distance and gradient.
// `grid` and `esdf-slice` are mapper commands (export_distance_grid, export_distance_slice)
// that write the file inside the mapper's output directory, as export-mesh does; they and
// `distance` need a mapper with planning.enabled.
// Exit status: 0 the command succeeded (status --all: every expected process is alive),
// 1 the mapper answered with a failure, 2 usage error, 3 no reply within the timeout (is
// cblox-mapper running, on the same LCM URL?), 4 status --all: an expected process was not
// heard, or its last heartbeat said it stopped.

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <chrono>
#include <cstdio>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include <cblox/command_reply_t.hpp>
#include <cblox/command_t.hpp>
#include <cblox/distance_reply_t.hpp>
#include <cblox/distance_request_t.hpp>
#include <cblox/heartbeat_t.hpp>
#include <cblox/map_status_t.hpp>
#include <lcm/lcm-cpp.hpp>

#include "daemon/common/cli.h"
#include "lcmtypes/wire_check.h"

namespace {

using Clock = std::chrono::steady_clock;

constexpr int kExitOk = 0;
constexpr int kExitFailed = 1;
constexpr int kExitUsage = 2;
constexpr int kExitNoReply = 3;
constexpr int kExitNotAlive = 4;

int64_t nowUtime() {
  return std::chrono::duration_cast<std::chrono::microseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

/// Handles `lcm` for `seconds` (or until `done()`); false when receiving fails.
template <typename Done>
bool listen(lcm::LCM& lcm, double seconds, Done done) {
  const auto deadline = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                           std::chrono::duration<double>(seconds));
  while (!done() && Clock::now() < deadline) {
    const auto left =
        std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now()).count();
    const int wait_ms = static_cast<int>(std::max<int64_t>(1, std::min<int64_t>(left, 200)));
    if (lcm.handleTimeout(wait_ms) < 0) return false;
  }
  return true;
}

// ---------------------------------------------------------------------------------------
// One command to the mapper.

struct Reply {
  std::optional<cblox::command_reply_t> reply;
  int64_t expected_id = 0;
  uint64_t refused = 0;  // replies that did not pass the wire check
  void onReply(const lcm::ReceiveBuffer* rbuf, const std::string&) {
    cblox::command_reply_t msg;
    if (!cblox::decodeChecked(rbuf->data, rbuf->data_size, &msg).ok()) {
      ++refused;
      return;
    }
    if (msg.command_id == expected_id) reply = std::move(msg);
  }
};

int runCommand(lcm::LCM& lcm, cblox::command_t command, const std::string& channel,
               const std::string& reply_channel, double timeout_s) {
  command.num_args = static_cast<int32_t>(command.arg_keys.size());
  command.utime = nowUtime();
  command.command_id = (static_cast<int64_t>(::getpid()) << 32) ^ (command.utime & 0xFFFFFFFF);
  command.sender = "cblox-ctl";
  Reply reply;
  reply.expected_id = command.command_id;
  lcm.subscribe(reply_channel, &Reply::onReply, &reply);
  if (lcm.publish(channel, &command) != 0) {
    std::fprintf(stderr, "cblox-ctl: cannot publish on %s\n", channel.c_str());
    return kExitUsage;
  }
  if (!listen(lcm, timeout_s, [&] { return reply.reply.has_value(); })) {
    std::fprintf(stderr, "cblox-ctl: LCM receive failed\n");
    return kExitUsage;
  }
  if (!reply.reply) {
    std::fprintf(
        stderr,
        "cblox-ctl: no reply to '%s' on %s within %.1f s (is cblox-mapper running on "
        "the same LCM URL?)%s\n",
        command.name.c_str(), reply_channel.c_str(), timeout_s,
        reply.refused > 0
            ? (" (" + std::to_string(reply.refused) + " malformed replies ignored)").c_str()
            : "");
    return kExitNoReply;
  }
  const cblox::command_reply_t& r = *reply.reply;
  std::printf("%s: %s\n", r.ok ? "ok" : "failed", r.message.c_str());
  for (int32_t i = 0; i < r.num_values && i < static_cast<int32_t>(r.values.size()) &&
                      i < static_cast<int32_t>(r.value_keys.size());
       ++i) {
    std::printf("  %s: %s\n", r.value_keys[i].c_str(), r.values[i].c_str());
  }
  return r.ok ? kExitOk : kExitFailed;
}

// ---------------------------------------------------------------------------------------
// distance: one request to the planning map.

struct DistanceReplyWait {
  std::optional<cblox::distance_reply_t> reply;
  int64_t expected_id = 0;
  uint64_t refused = 0;  // replies that did not pass the wire check
  void onReply(const lcm::ReceiveBuffer* rbuf, const std::string&) {
    cblox::distance_reply_t msg;
    if (!cblox::decodeChecked(rbuf->data, rbuf->data_size, &msg).ok()) {
      ++refused;
      return;
    }
    if (msg.request_id == expected_id) reply = std::move(msg);
  }
};

const char* distanceStateName(int8_t state) {
  switch (state) {
    case cblox::distance_reply_t::FREE:
      return "free";
    case cblox::distance_reply_t::OCCUPIED:
      return "occupied";
    case cblox::distance_reply_t::UNKNOWN:
      return "unknown";
    case cblox::distance_reply_t::INVALID_POINT:
      return "invalid point";
    default:
      return "?";
  }
}

int runDistance(lcm::LCM& lcm, const std::vector<double>& xyz, const std::string& channel,
                const std::string& reply_channel, double timeout_s) {
  cblox::distance_request_t request;
  request.utime = nowUtime();
  request.request_id = (static_cast<int64_t>(::getpid()) << 32) ^ (request.utime & 0xFFFFFFFF);
  request.map_epoch = 0;
  for (size_t i = 0; i + 2 < xyz.size(); i += 3) request.points.push_back({xyz[i], xyz[i + 1], xyz[i + 2]});
  request.num_points = static_cast<int32_t>(request.points.size());
  DistanceReplyWait wait;
  wait.expected_id = request.request_id;
  lcm.subscribe(reply_channel, &DistanceReplyWait::onReply, &wait);
  if (lcm.publish(channel, &request) != 0) {
    std::fprintf(stderr, "cblox-ctl: cannot publish on %s\n", channel.c_str());
    return kExitUsage;
  }
  if (!listen(lcm, timeout_s, [&] { return wait.reply.has_value(); })) {
    std::fprintf(stderr, "cblox-ctl: LCM receive failed\n");
    return kExitUsage;
  }
  if (!wait.reply) {
    std::fprintf(stderr,
                 "cblox-ctl: no distance reply on %s within %.1f s (is cblox-mapper running on "
                 "the same LCM URL?)\n",
                 reply_channel.c_str(), timeout_s);
    return kExitNoReply;
  }
  const cblox::distance_reply_t& r = *wait.reply;
  const bool answered = r.status == cblox::distance_reply_t::STATUS_OK ||
                        r.status == cblox::distance_reply_t::STATUS_EPOCH_CHANGED;
  std::printf("%s (map epoch %lld)%s%s\n", answered ? "ok" : "failed",
              static_cast<long long>(r.map_epoch), r.message.empty() ? "" : ": ",
              r.message.c_str());
  const size_t n = std::min({static_cast<size_t>(std::max(r.num_points, 0)), r.state.size(),
                             r.distance.size(), r.gradient.size(), request.points.size()});
  for (size_t k = 0; k < n; ++k) {
    const std::vector<double>& p = request.points[k];
    std::printf("  (%.3f, %.3f, %.3f): %s", p[0], p[1], p[2], distanceStateName(r.state[k]));
    if (std::isfinite(r.distance[k])) {
      const bool capped = r.state[k] == cblox::distance_reply_t::FREE &&
                          r.distance[k] >= r.max_distance_m;
      std::printf(", distance %s%.3f m", capped ? ">= " : "", static_cast<double>(r.distance[k]));
    }
    const std::vector<float>& g = r.gradient[k];
    if (g.size() == 3 && std::isfinite(g[0])) {
      std::printf(", gradient (%.3f, %.3f, %.3f)", static_cast<double>(g[0]),
                  static_cast<double>(g[1]), static_cast<double>(g[2]));
    }
    std::printf("\n");
  }
  return answered ? kExitOk : kExitFailed;
}

// ---------------------------------------------------------------------------------------
// status --all: the heartbeats of every process.

/// "cblox-mapper" -> "mapper"; other names unchanged.
std::string shortName(const std::string& process) {
  const std::string prefix = "cblox-";
  return process.rfind(prefix, 0) == 0 ? process.substr(prefix.size()) : process;
}

std::optional<int64_t> counter(const cblox::heartbeat_t& hb, const std::string& name) {
  const size_t n = std::min(hb.counter_names.size(), hb.counter_values.size());
  for (size_t i = 0; i < n; ++i) {
    if (hb.counter_names[i] == name) return hb.counter_values[i];
  }
  return std::nullopt;
}

/// The first of `names` the heartbeat carries.
std::optional<std::string> firstCounter(const cblox::heartbeat_t& hb,
                                        std::initializer_list<const char*> names) {
  for (const char* name : names) {
    if (counter(hb, name)) return std::string(name);
  }
  return std::nullopt;
}

/// The process's own state without the input-silence prefix ("input silent: ...; running"
/// -> "running").
std::string baseState(const std::string& state) {
  if (state.rfind("input silent: ", 0) != 0) return state;
  const size_t separator = state.find("; ");
  return separator == std::string::npos ? std::string() : state.substr(separator + 2);
}

/// A process's last heartbeat says it has ended (cblox processes send one on the way out).
bool saysEnded(const cblox::heartbeat_t& hb) {
  const std::string state = baseState(hb.state);
  return state == "stopped" || state == "finished";
}

struct Heard {
  cblox::heartbeat_t first;  // the first heartbeat heard of the newest pid
  cblox::heartbeat_t last;   // the newest
  int count = 0;
};

struct StatusListener {
  std::map<std::string, Heard> processes;  // by process name
  std::optional<cblox::map_status_t> map_status;
  uint64_t refused = 0;

  void onHeartbeat(const lcm::ReceiveBuffer* rbuf, const std::string&) {
    cblox::heartbeat_t hb;
    if (!cblox::decodeChecked(rbuf->data, rbuf->data_size, &hb).ok()) {
      ++refused;
      return;
    }
    Heard& heard = processes[hb.process];
    if (heard.count == 0 || heard.last.pid != hb.pid) {  // first, or the process restarted
      heard.first = hb;
      heard.count = 0;
    }
    if (heard.count == 0 || hb.utime >= heard.last.utime) heard.last = hb;
    ++heard.count;
  }
  void onMapStatus(const lcm::ReceiveBuffer* rbuf, const std::string&) {
    cblox::map_status_t msg;
    if (!cblox::decodeChecked(rbuf->data, rbuf->data_size, &msg).ok()) {
      ++refused;
      return;
    }
    if (!map_status || msg.utime >= map_status->utime) map_status = std::move(msg);
  }
};

std::string format(const char* fmt, double value) {
  char text[64];
  std::snprintf(text, sizeof(text), fmt, value);
  return text;
}

/// One row of the table (process heard).
struct Row {
  std::string name, pid, last;
  // "-" where the heartbeat lacks the counters (constructed, not assigned: GCC 12 warns
  // falsely, -Wrestrict, on assigning a literal here).
  std::string rate{"-"}, dropped{"-"}, queue{"-"}, cpu{"-"}, rss{"-"}, input{"-"};
  std::string state;
};

Row describe(const std::string& name, const Heard& heard, int64_t now_utime) {
  const cblox::heartbeat_t& hb = heard.last;
  Row row;
  row.name = name;
  row.pid = std::to_string(hb.pid);
  row.last =
      format("%.1fs", std::max<double>(0.0, static_cast<double>(now_utime - hb.utime) * 1e-6));
  // Between the first and the last heartbeat of this pid.
  const double dt_s = static_cast<double>(hb.utime - heard.first.utime) * 1e-6;
  const bool two = heard.count >= 2 && dt_s > 0.0;
  if (const auto frames = firstCounter(
          hb, {"frames_published", "frames_processed", "frames_integrated", "frames_received"})) {
    if (two) {
      const auto a = counter(heard.first, *frames);
      const auto b = counter(hb, *frames);
      if (a && b) row.rate = format("%.1f", static_cast<double>(*b - *a) / dt_s);
    }
  }
  if (const auto name_dropped = firstCounter(hb, {"frames_dropped", "source_gaps"})) {
    row.dropped = std::to_string(*counter(hb, *name_dropped));
  }
  if (const auto name_queue = firstCounter(hb, {"queue_depth", "frames_pending"})) {
    row.queue = std::to_string(*counter(hb, *name_queue));
  }
  if (const auto cpu = counter(hb, "cpu_ms")) {
    const auto cpu_first = counter(heard.first, "cpu_ms");
    if (two && cpu_first) {
      row.cpu = format("%.0f%%", 100.0 * static_cast<double>(*cpu - *cpu_first) / (dt_s * 1000.0));
    } else {
      row.cpu = format("%.1fs", static_cast<double>(*cpu) / 1000.0);
    }
  }
  if (const auto rss = counter(hb, "rss_kib")) {
    row.rss = format("%.0fMiB", static_cast<double>(*rss) / 1024.0);
  }
  const auto silent = counter(hb, "input_silent");
  const auto age = counter(hb, "input_age_ms");
  if (silent && age) {
    row.input =
        (*silent != 0 ? "SILENT " : "ok ") + format("%.1fs", static_cast<double>(*age) / 1000.0);
  }
  row.state = hb.state;
  return row;
}

std::vector<std::string> splitList(const std::string& text) {
  std::vector<std::string> out;
  size_t begin = 0;
  while (begin <= text.size()) {
    const size_t end = std::min(text.find(',', begin), text.size());
    const std::string item = text.substr(begin, end - begin);
    if (!item.empty()) out.push_back(shortName(item));
    begin = end + 1;
  }
  return out;
}

int runStatusAll(lcm::LCM& lcm, const std::string& heartbeat_channel,
                 const std::string& map_status_channel, double listen_s,
                 const std::vector<std::string>& expected) {
  StatusListener listener;
  lcm.subscribe(heartbeat_channel, &StatusListener::onHeartbeat, &listener);
  lcm.subscribe(map_status_channel, &StatusListener::onMapStatus, &listener);
  if (!listen(lcm, listen_s, [] { return false; })) {
    std::fprintf(stderr, "cblox-ctl: LCM receive failed\n");
    return kExitUsage;
  }
  const int64_t now = nowUtime();

  // Expected processes first (in the order given), then every other one heard.
  std::vector<std::string> order = expected;
  std::map<std::string, const Heard*> by_name;
  for (const auto& [process, heard] : listener.processes) by_name[shortName(process)] = &heard;
  for (const auto& [name, heard] : by_name) {
    if (std::find(order.begin(), order.end(), name) == order.end()) order.push_back(name);
  }

  std::printf("cblox status: heartbeats on %s for %.1f s\n", heartbeat_channel.c_str(), listen_s);
  const char* header_fmt = "%-10s %7s %6s %8s %7s %5s %6s %7s %-12s %s\n";
  std::printf(header_fmt, "process", "pid", "last", "frames/s", "dropped", "queue", "cpu", "rss",
              "input", "state");
  std::vector<std::string> not_alive;
  for (const std::string& name : order) {
    const auto it = by_name.find(name);
    const bool is_expected = std::find(expected.begin(), expected.end(), name) != expected.end();
    if (it == by_name.end()) {
      std::printf("%-10s %7s  not heard (no heartbeat in %.1f s)\n", name.c_str(), "-", listen_s);
      if (is_expected) not_alive.push_back(name);
      continue;
    }
    const Row r = describe(name, *it->second, now);
    std::printf(header_fmt, r.name.c_str(), r.pid.c_str(), r.last.c_str(), r.rate.c_str(),
                r.dropped.c_str(), r.queue.c_str(), r.cpu.c_str(), r.rss.c_str(), r.input.c_str(),
                r.state.c_str());
    if (is_expected && saysEnded(it->second->last)) not_alive.push_back(name);
  }
  // Processes that checkpoint without a map status of their own (the tracker): one line each.
  for (const std::string& name : order) {
    const auto it = by_name.find(name);
    if (it == by_name.end() || name == "mapper") continue;
    const cblox::heartbeat_t& hb = it->second->last;
    const auto generation = counter(hb, "checkpoint_generation");
    const int64_t written = counter(hb, "checkpoints_written").value_or(0);
    const int64_t failed = counter(hb, "checkpoint_failures").value_or(0);
    if (generation && (*generation > 0 || written > 0 || failed > 0)) {
      std::printf("%s checkpoints: generation %lld, %lld written, %lld failed\n", name.c_str(),
                  static_cast<long long>(*generation), static_cast<long long>(written),
                  static_cast<long long>(failed));
    }
  }
  if (listener.map_status) {
    const cblox::map_status_t& m = *listener.map_status;
    std::printf(
        "map: %d subvolumes (active %lld), %lld blocks, %.1f MiB; frames %lld integrated, %lld "
        "dropped, %lld rejected; integration median %.1f ms, p99 %.1f ms; %lld fused\n",
        m.num_subvolumes, static_cast<long long>(m.active_subvolume_id),
        static_cast<long long>(m.num_blocks), static_cast<double>(m.memory_bytes) / 1048576.0,
        static_cast<long long>(m.frames_integrated), static_cast<long long>(m.frames_dropped),
        static_cast<long long>(m.frames_rejected), static_cast<double>(m.integration_ms_median),
        static_cast<double>(m.integration_ms_p99), static_cast<long long>(m.subvolumes_fused));
    if (!m.checkpoint_dir.empty()) {
      const std::string age =
          m.last_checkpoint_utime > 0
              ? format("%.1f s ago", static_cast<double>(now - m.last_checkpoint_utime) * 1e-6)
              : std::string("none yet");
      std::printf(
          "checkpoints: %s generation %lld (%s, %.1f ms), %lld written, %lld failed\n",
          m.checkpoint_dir.c_str(), static_cast<long long>(m.checkpoint_generation), age.c_str(),
          static_cast<double>(m.last_checkpoint_ms), static_cast<long long>(m.checkpoints_written),
          static_cast<long long>(m.checkpoint_failures));
    }
  } else {
    std::printf("map: no %s in %.1f s\n", map_status_channel.c_str(), listen_s);
  }
  if (listener.refused > 0) {
    std::printf("note: %llu malformed messages ignored\n",
                static_cast<unsigned long long>(listener.refused));
  }
  std::printf(
      "cpu: share of one core between the first and last heartbeat heard (total CPU "
      "time in s when only one was heard)\n");
  if (expected.empty()) return kExitOk;
  if (not_alive.empty()) {
    std::printf("alive: all expected processes (");
  } else {
    std::printf("NOT ALIVE: ");
    for (size_t i = 0; i < not_alive.size(); ++i) {
      std::printf("%s%s", i ? ", " : "", not_alive[i].c_str());
    }
    std::printf(" (expected: ");
  }
  for (size_t i = 0; i < expected.size(); ++i) {
    std::printf("%s%s", i ? ", " : "", expected[i].c_str());
  }
  std::printf(")\n");
  return not_alive.empty() ? kExitOk : kExitNotAlive;
}

}  // namespace

int main(int argc, char** argv) {
  std::string url, channel = "CBLOX_CMD", reply_channel = "CBLOX_CMD_REPLY";
  std::string heartbeat_channel = "CBLOX_HEARTBEAT", map_status_channel = "CBLOX_MAP_STATUS";
  double timeout_s = 10.0, listen_s = 1.5;
  bool all = false;
  std::string expect = "capture,tracker,mapper";
  std::string verb, path, out, box;
  std::vector<std::string> operands;
  std::string distance_channel = "CBLOX_DISTANCE_REQUEST",
              distance_reply_channel = "CBLOX_DISTANCE_REPLY";
  double z = std::nan(""), resolution = 0.0;
  CLI::App app{
      "cblox-ctl: sends one command to the mapper over LCM and prints its reply, or (status\n"
      "--all) summarises the health of every cblox process from their heartbeats.",
      "cblox-ctl"};
  app.add_option("command", verb,
                 "status: print the mapper's statistics; status --all: one row per process\n"
                 "(heartbeats for --listen seconds) and the map; export-mesh PATH: write the\n"
                 "global mesh (PLY); export-submap-meshes DIR: one mesh per subvolume,\n"
                 "coloured by subvolume; save-map DIR: save the map (a map directory);\n"
                 "load-map DIR: load a saved map into a mapper whose map is empty;\n"
                 "distance X Y Z [X Y Z ...]: the planning map's state, distance and gradient\n"
                 "at points of G; grid --box x0,y0,z0,x1,y1,z1 --out FILE: the distance field\n"
                 "over a box as a PLY point cloud (observed cells, coloured by distance);\n"
                 "esdf-slice --z H --out FILE: a PNG slice of the distance field at height H;\n"
                 "mesh-refresh: the mesh stream resends every block (for live viewers)")
      ->required()
      ->type_name("COMMAND");
  CLI::Option* operand_option =
      app.add_option("args", operands,
                     "PATH or DIR, relative to the mapper's output directory (load-map: any);\n"
                     "distance: X Y Z of each point, metres")
          ->type_name("ARG")
          ->allow_extra_args();
  CLI::Option* out_option =
      app.add_option("--out", out, "grid, esdf-slice: the file, in the mapper's output directory")
          ->type_name("FILE");
  CLI::Option* box_option =
      app.add_option("--box", box, "grid: x0,y0,z0,x1,y1,z1 (metres, G)")->type_name("BOX");
  CLI::Option* z_option = app.add_option("--z", z, "esdf-slice: height of the slice, metres");
  CLI::Option* resolution_option =
      app.add_option("--resolution", resolution,
                     "grid, esdf-slice: cell edge, metres (default: the map's voxel size)")
          ->check(cblox::finiteNumber(cblox::NumberBound::kPositive));
  app.add_option("--distance-channel", distance_channel, "distance: request channel")
      ->capture_default_str();
  app.add_option("--distance-reply-channel", distance_reply_channel, "distance: reply channel")
      ->capture_default_str();
  app.add_option("--lcm-url", url, "LCM URL (default: LCM's default)")->type_name("URL");
  app.add_option("--timeout", timeout_s, "seconds to wait for the mapper's reply")
      ->check(cblox::finiteNumber(cblox::NumberBound::kPositive))
      ->capture_default_str();
  app.add_option("--channel", channel, "command channel")->capture_default_str();
  app.add_option("--reply-channel", reply_channel, "reply channel")->capture_default_str();
  CLI::Option* all_flag = app.add_flag(
      "--all", all, "status --all: every process's heartbeat, not the mapper's status");
  CLI::Option* listen_option =
      app.add_option("--listen", listen_s, "status --all: seconds to listen")
          ->check(cblox::finiteNumber(cblox::NumberBound::kPositive))
          ->capture_default_str();
  CLI::Option* expect_option =
      app.add_option("--expect", expect,
                     "status --all: processes that must be alive (comma list; '' = none)")
          ->capture_default_str();
  app.add_option("--heartbeat-channel", heartbeat_channel, "status --all: heartbeat channel")
      ->capture_default_str();
  app.add_option("--map-status-channel", map_status_channel, "status --all: map status channel")
      ->capture_default_str();
  app.footer(
      "Exit status: 0 ok, 1 the mapper reported a failure, 2 usage, 3 no reply,\n"
      "4 status --all: an expected process is not alive.");
  if (const std::optional<int> code = cblox::parseCommandLine(app, argc, argv)) return *code;
  const bool status_all = verb == "status" && all;
  if ((all_flag->count() > 0 || listen_option->count() > 0 || expect_option->count() > 0) &&
      !status_all) {
    std::fprintf(stderr, "cblox-ctl: --all, --listen and --expect go with 'status --all'\n");
    return kExitUsage;
  }
  const bool is_grid = verb == "grid", is_slice = verb == "esdf-slice";
  if ((out_option->count() > 0 || resolution_option->count() > 0) && !is_grid && !is_slice) {
    std::fprintf(stderr, "cblox-ctl: --out and --resolution go with 'grid' and 'esdf-slice'\n");
    return kExitUsage;
  }
  if (is_grid && box_option->count() == 0) {
    std::fprintf(stderr, "cblox-ctl: grid needs --box x0,y0,z0,x1,y1,z1\n");
    return kExitUsage;
  }
  if ((box_option->count() > 0 && !is_grid) || (z_option->count() > 0 && !is_slice)) {
    std::fprintf(stderr, "cblox-ctl: --box goes with 'grid', --z with 'esdf-slice'\n");
    return kExitUsage;
  }
  std::vector<double> xyz;
  if (verb == "distance") {
    for (const std::string& operand : operands) {
      char* end = nullptr;
      const double v = std::strtod(operand.c_str(), &end);
      if (operand.empty() || *end != '\0' || !std::isfinite(v)) {
        std::fprintf(stderr, "cblox-ctl: distance: '%s' is not a finite number\n",
                     operand.c_str());
        return kExitUsage;
      }
      xyz.push_back(v);
    }
    if (xyz.empty() || xyz.size() % 3 != 0 ||
        xyz.size() / 3 > static_cast<size_t>(cblox::distance_request_t::MAX_POINTS)) {
      std::fprintf(stderr, "cblox-ctl: distance needs X Y Z for each of 1 to %d points\n",
                   cblox::distance_request_t::MAX_POINTS);
      return kExitUsage;
    }
  }
  cblox::command_t command;
  const bool has_path = operand_option->count() > 0 && operands.size() == 1;
  if (has_path) path = operands.front();
  if (operand_option->count() > 0 && operands.size() != 1 && verb != "distance") {
    std::fprintf(stderr, "cblox-ctl: '%s' takes one PATH or DIR\n", verb.c_str());
    return kExitUsage;
  }
  if (verb == "status" && !has_path) {
    command.name = "status";
  } else if (verb == "mesh-refresh" && operand_option->count() == 0) {
    command.name = "mesh_refresh";
  } else if (verb == "export-mesh" && has_path) {
    command.name = "export_mesh";
    command.arg_keys = {"path"};
    command.arg_values = {path};
  } else if (verb == "export-submap-meshes" && has_path) {
    command.name = "export_submap_meshes";
    command.arg_keys = {"path"};
    command.arg_values = {path};
  } else if (verb == "save-map" && has_path) {
    command.name = "save_map";
    command.arg_keys = {"path"};
    command.arg_values = {path};
  } else if (verb == "load-map" && has_path) {
    command.name = "load_map";
    command.arg_keys = {"path"};
    command.arg_values = {path};
  } else if (verb == "distance") {
    // a distance_request_t, not a command
  } else if ((is_grid || is_slice) && !has_path && out_option->count() > 0 &&
             (is_grid || z_option->count() > 0)) {
    command.name = is_grid ? "export_distance_grid" : "export_distance_slice";
    command.arg_keys = {"path"};
    command.arg_values = {out};
    if (is_grid) {
      command.arg_keys.push_back("box");
      command.arg_values.push_back(box);
    } else {
      char text[64];
      std::snprintf(text, sizeof text, "%.17g", z);
      command.arg_keys.push_back("z");
      command.arg_values.push_back(text);
    }
    if (resolution_option->count() > 0) {
      char text[64];
      std::snprintf(text, sizeof text, "%.17g", resolution);
      command.arg_keys.push_back("resolution");
      command.arg_values.push_back(text);
    }
  } else {
    std::fprintf(stderr, "cblox-ctl: unknown command or wrong arguments: '%s' (see --help)\n",
                 verb.c_str());
    return kExitUsage;
  }

  lcm::LCM lcm(url);
  if (!lcm.good()) {
    std::fprintf(stderr, "cblox-ctl: cannot open LCM (url '%s')\n", url.c_str());
    return kExitUsage;
  }
  if (status_all) {
    return runStatusAll(lcm, heartbeat_channel, map_status_channel, listen_s, splitList(expect));
  }
  if (verb == "distance") {
    return runDistance(lcm, xyz, distance_channel, distance_reply_channel, timeout_s);
  }
  return runCommand(lcm, command, channel, reply_channel, timeout_s);
}
