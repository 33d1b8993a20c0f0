// cblox-bench-distance-lcm: a planner's view of the distance service. Sends distance
// requests of --points random points in --box to a running cblox-mapper over LCM, one at a
// time at --rate Hz (or back to back with --rate 0), and measures each round trip from
// publish to the reply's arrival. Prints the median, p90, p99 and max round trip, the replies'
// statuses and the points' states, and the mapper's own answer times from its last heartbeat
// (distance_answer_us_median / _p99: a request's arrival at the mapper to its reply's
// publication), and writes them as JSON with --json.
//
//   cblox-bench-distance-lcm --lcm-url URL --requests 200 --points 4096
//       --box=0,0,0,5,6.5,2.7 --rate 10
//
// Exit status: 0 done, 1 a request had no reply within --timeout, 2 usage.

#include <unistd.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <optional>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include <cblox/distance_reply_t.hpp>
#include <cblox/distance_request_t.hpp>
#include <cblox/heartbeat_t.hpp>
#include <lcm/lcm-cpp.hpp>
#include <nlohmann/json.hpp>

#include "core/common/quantile.h"
#include "core/io/text_fields.h"
#include "daemon/common/cli.h"
#include "lcmtypes/wire_check.h"

namespace {

using Clock = std::chrono::steady_clock;

struct Waiter {
  int64_t expected = 0;
  std::optional<cblox::distance_reply_t> reply;
  Clock::time_point arrived;
  void onReply(const lcm::ReceiveBuffer* rbuf, const std::string&) {
    cblox::distance_reply_t msg;
    if (!cblox::decodeChecked(rbuf->data, rbuf->data_size, &msg).ok()) return;
    if (msg.request_id != expected) return;
    arrived = Clock::now();
    reply = std::move(msg);
  }
};

/// The mapper's answer-time counters from its latest heartbeat (-1 until one arrives).
struct MapperAnswerTimes {
  int64_t median_us = -1, p99_us = -1;
  void onHeartbeat(const lcm::ReceiveBuffer* rbuf, const std::string&) {
    cblox::heartbeat_t msg;
    if (!cblox::decodeChecked(rbuf->data, rbuf->data_size, &msg).ok()) return;
    if (msg.process != "cblox-mapper") return;
    for (size_t i = 0; i < msg.counter_names.size() && i < msg.counter_values.size(); ++i) {
      if (msg.counter_names[i] == "distance_answer_us_median") median_us = msg.counter_values[i];
      if (msg.counter_names[i] == "distance_answer_us_p99") p99_us = msg.counter_values[i];
    }
  }
};

}  // namespace

int main(int argc, char** argv) {
  std::string url, box_text = "0,0,0,5,6.5,2.7", json_path;
  int requests = 200, points = 4096;
  double rate = 10.0, timeout_s = 5.0;
  CLI::App app{"cblox-bench-distance-lcm: round trips of distance requests to cblox-mapper",
               "cblox-bench-distance-lcm"};
  app.add_option("--lcm-url", url, "LCM URL (default: LCM's default)");
  app.add_option("--requests", requests, "requests to send")->check(CLI::PositiveNumber)
      ->capture_default_str();
  app.add_option("--points", points, "points per request (at most 4096)")
      ->check(CLI::Range(1, static_cast<int>(cblox::distance_request_t::MAX_POINTS)))
      ->capture_default_str();
  app.add_option("--box", box_text, "x0,y0,z0,x1,y1,z1: where the points are drawn (G, metres)")
      ->capture_default_str();
  app.add_option("--rate", rate, "requests per second; 0 = back to back")
      ->check(cblox::finiteNumber(cblox::NumberBound::kNonNegative))
      ->capture_default_str();
  app.add_option("--timeout", timeout_s, "seconds to wait for one reply")
      ->check(cblox::finiteNumber(cblox::NumberBound::kPositive))
      ->capture_default_str();
  app.add_option("--json", json_path, "write the figures here too");
  if (const std::optional<int> code = cblox::parseCommandLine(app, argc, argv)) return *code;
  std::string error;
  const std::optional<std::vector<double>> box = cblox::parseNumbers(box_text, 6, &error);
  if (!box) {
    std::fprintf(stderr, "cblox-bench-distance-lcm: --box: %s\n", error.c_str());
    return 2;
  }
  lcm::LCM lcm(url);
  if (!lcm.good()) {
    std::fprintf(stderr, "cblox-bench-distance-lcm: cannot open LCM (url '%s')\n", url.c_str());
    return 2;
  }
  Waiter waiter;
  lcm.subscribe("CBLOX_DISTANCE_REPLY", &Waiter::onReply, &waiter);
  MapperAnswerTimes mapper_times;
  lcm.subscribe("CBLOX_HEARTBEAT", &MapperAnswerTimes::onHeartbeat, &mapper_times);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> ux((*box)[0], (*box)[3]), uy((*box)[1], (*box)[4]),
      uz((*box)[2], (*box)[5]);
  std::vector<double> round_trip_ms;
  std::array<uint64_t, 5> statuses{}, states{};
  const auto period = rate > 0.0 ? std::chrono::duration<double>(1.0 / rate)
                                 : std::chrono::duration<double>(0.0);
  const Clock::time_point start = Clock::now();
  for (int i = 0; i < requests; ++i) {
    std::this_thread::sleep_until(start + std::chrono::duration_cast<Clock::duration>(period * i));
    cblox::distance_request_t request;
    request.utime = 0;
    request.request_id = (static_cast<int64_t>(::getpid()) << 32) | i;
    request.map_epoch = 0;
    for (int k = 0; k < points; ++k) request.points.push_back({ux(rng), uy(rng), uz(rng)});
    request.num_points = points;
    waiter.expected = request.request_id;
    waiter.reply.reset();
    const Clock::time_point sent = Clock::now();
    lcm.publish("CBLOX_DISTANCE_REQUEST", &request);
    while (!waiter.reply && Clock::now() - sent < std::chrono::duration<double>(timeout_s)) {
      lcm.handleTimeout(10);
    }
    if (!waiter.reply) {
      std::fprintf(stderr, "cblox-bench-distance-lcm: no reply to request %d within %.1f s\n", i,
                   timeout_s);
      return 1;
    }
    round_trip_ms.push_back(std::chrono::duration<double, std::milli>(waiter.arrived - sent).count());
    const cblox::distance_reply_t& r = *waiter.reply;
    if (r.status >= 0 && r.status < 5) ++statuses[static_cast<size_t>(r.status)];
    for (const int8_t s : r.state) {
      if (s >= 0 && s < 4) ++states[static_cast<size_t>(s)];
    }
  }
  const double median = cblox::quantile(&round_trip_ms, 0.5);
  const double p90 = cblox::quantile(&round_trip_ms, 0.9);
  const double p99 = cblox::quantile(&round_trip_ms, 0.99);
  const double max = *std::max_element(round_trip_ms.begin(), round_trip_ms.end());
  std::printf(
      "%d requests of %d points: round trip median %.2f ms, p90 %.2f, p99 %.2f, max %.2f; "
      "statuses ok %llu, epoch changed %llu, too many %llu, no planning map %llu, busy %llu; "
      "points unknown %llu, free %llu, occupied %llu, invalid %llu\n",
      requests, points, median, p90, p99, max, static_cast<unsigned long long>(statuses[0]),
      static_cast<unsigned long long>(statuses[1]), static_cast<unsigned long long>(statuses[2]),
      static_cast<unsigned long long>(statuses[3]), static_cast<unsigned long long>(statuses[4]),
      static_cast<unsigned long long>(states[0]), static_cast<unsigned long long>(states[1]),
      static_cast<unsigned long long>(states[2]), static_cast<unsigned long long>(states[3]));
  if (mapper_times.median_us >= 0) {
    std::printf("mapper's answer time (arrival to reply published, its last heartbeat): "
                "median %.2f ms, p99 %.2f ms\n",
                static_cast<double>(mapper_times.median_us) / 1000.0,
                static_cast<double>(mapper_times.p99_us) / 1000.0);
  }
  if (!json_path.empty()) {
    nlohmann::json j;
    j["requests"] = requests;
    j["points"] = points;
    j["round_trip_ms"] = {{"median", median}, {"p90", p90}, {"p99", p99}, {"max", max}};
    j["statuses"] = statuses;
    j["states"] = states;
    if (mapper_times.median_us >= 0) {
      j["mapper_answer_ms"] = {{"median", static_cast<double>(mapper_times.median_us) / 1000.0},
                               {"p99", static_cast<double>(mapper_times.p99_us) / 1000.0}};
    }
    std::ofstream(json_path) << j.dump(2) << "\n";
  }
  return 0;
}
