// InputWatch (input-silence health) with an injected clock: exact silence boundaries, the log
// lines (one when silence begins, one when input returns), heartbeat counters and state; and
// MessageGuard feeding it (in-process LCM, memq://): only messages that pass the wire check
// on a watched channel count as input.

#include "daemon/common/input_watch.h"

#include <chrono>
#include <cmath>
#include <limits>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <cblox/heartbeat_t.hpp>
#include <cblox/map_status_t.hpp>
#include <lcm/lcm-cpp.hpp>

#include "daemon/common/heartbeat.h"
#include "daemon/common/message_guard.h"

namespace cblox {
namespace {

using Clock = InputWatch::Clock;
using std::chrono::milliseconds;

/// A clock the test moves by hand, and the log lines the watch wrote.
struct Fixture {
  Clock::time_point now = Clock::time_point{} + std::chrono::hours(1);
  std::vector<std::string> lines;
  InputWatch::LogSink sink() {
    return [this](const std::string& line) { lines.push_back(line); };
  }
  InputWatch::NowFn clock() {
    return [this] { return now; };
  }
  void advance(int ms) { now += milliseconds(ms); }
};

std::map<std::string, int64_t> counters(const heartbeat_t& hb) {
  std::map<std::string, int64_t> out;
  for (int i = 0; i < hb.num_counters; ++i) out[hb.counter_names[i]] = hb.counter_values[i];
  return out;
}

TEST(InputWatchTest, SilentExactlyAtTheLimitWithOneLogLine) {
  Fixture f;
  InputWatch watch("cblox-test", 2.0, f.sink(), f.clock());
  watch.watch("CBLOX_DEPTH");
  f.advance(1999);
  InputWatch::Report r = watch.check();
  EXPECT_FALSE(r.silent);
  ASSERT_EQ(r.inputs.size(), 1u);
  EXPECT_FALSE(r.inputs[0].heard);
  EXPECT_NEAR(r.inputs[0].age_s, 1.999, 1e-9);
  EXPECT_EQ(r.description, "");
  EXPECT_TRUE(f.lines.empty());

  f.advance(1);  // 2.000 s: silent
  r = watch.check();
  EXPECT_TRUE(r.silent);
  EXPECT_TRUE(r.inputs[0].silent);
  EXPECT_EQ(r.silences, 1u);
  EXPECT_EQ(r.description, "input silent: CBLOX_DEPTH for 2.0 s (none yet)");
  ASSERT_EQ(f.lines.size(), 1u);
  EXPECT_EQ(
      f.lines[0],
      "cblox-test: input silent: nothing on CBLOX_DEPTH since start, 2.0 s ago (limit 2.0 s)");

  // Still silent: no second line, the same silence.
  f.advance(3200);
  r = watch.check();
  EXPECT_TRUE(r.silent);
  EXPECT_EQ(r.silences, 1u);
  EXPECT_EQ(r.description, "input silent: CBLOX_DEPTH for 5.2 s (none yet)");
  EXPECT_EQ(f.lines.size(), 1u);
}

TEST(InputWatchTest, ArrivalEndsTheSilenceWithOneLineAndResetsTheAge) {
  Fixture f;
  InputWatch watch("cblox-test", 2.0, f.sink(), f.clock());
  watch.watch("CBLOX_STEREO");
  watch.arrived("CBLOX_STEREO");
  f.advance(2500);
  InputWatch::Report r = watch.check();
  ASSERT_TRUE(r.silent);
  EXPECT_EQ(r.description, "input silent: CBLOX_STEREO for 2.5 s");  // heard before
  ASSERT_EQ(f.lines.size(), 1u);
  EXPECT_EQ(f.lines[0],
            "cblox-test: input silent: nothing on CBLOX_STEREO for 2.5 s (limit 2.0 s)");

  f.advance(2800);
  watch.arrived("CBLOX_STEREO");
  ASSERT_EQ(f.lines.size(), 2u);
  EXPECT_EQ(f.lines[1], "cblox-test: input back: CBLOX_STEREO after 5.3 s of silence");
  watch.arrived("CBLOX_STEREO");  // the next one says nothing
  EXPECT_EQ(f.lines.size(), 2u);

  f.advance(300);
  r = watch.check();
  EXPECT_FALSE(r.silent);
  EXPECT_TRUE(r.inputs[0].heard);
  EXPECT_NEAR(r.inputs[0].age_s, 0.3, 1e-9);
  EXPECT_EQ(r.silences, 1u);
  EXPECT_EQ(f.lines.size(), 2u);

  // A second silence is counted and logged again.
  f.advance(1700);
  r = watch.check();
  EXPECT_TRUE(r.silent);
  EXPECT_EQ(r.silences, 2u);
  EXPECT_EQ(f.lines.size(), 3u);
}

TEST(InputWatchTest, SilenceNoCheckSawIsLoggedAndCountedOnArrival) {
  Fixture f;
  InputWatch watch("cblox-test", 2.0, f.sink(), f.clock());
  watch.watch("A");
  watch.arrived("A");
  f.advance(1000);
  EXPECT_FALSE(watch.check().silent);
  f.advance(1400);  // 2.4 s without a check in between the limit and the arrival
  watch.arrived("A");
  ASSERT_EQ(f.lines.size(), 1u);
  EXPECT_EQ(f.lines[0], "cblox-test: input silent and back: nothing on A for 2.4 s (limit 2.0 s)");
  const InputWatch::Report r = watch.check();
  EXPECT_FALSE(r.silent);
  EXPECT_EQ(r.silences, 1u);
  // A gap just under the limit is no silence.
  f.advance(1999);
  watch.arrived("A");
  EXPECT_EQ(f.lines.size(), 1u);
  EXPECT_EQ(watch.check().silences, 1u);
}

TEST(InputWatchTest, SeveralInputsOnlyTheSilentOnesAreNamed) {
  Fixture f;
  InputWatch watch("cblox-mapper", 2.0, f.sink(), f.clock());
  watch.watch("CBLOX_DEPTH");
  watch.watch("CBLOX_FRAME_POSE");
  watch.watch("CBLOX_DEPTH");  // twice: once
  EXPECT_TRUE(watch.watches("CBLOX_FRAME_POSE"));
  EXPECT_FALSE(watch.watches("CBLOX_GT_POSE"));
  watch.arrived("CBLOX_DEPTH");
  watch.arrived("CBLOX_FRAME_POSE");
  for (int i = 0; i < 6; ++i) {  // depth keeps coming every 0.5 s, poses stop
    f.advance(500);
    watch.arrived("CBLOX_DEPTH");
    watch.arrived("CBLOX_GT_POSE");  // not watched: ignored
  }
  const InputWatch::Report r = watch.check();
  ASSERT_EQ(r.inputs.size(), 2u);
  EXPECT_FALSE(r.inputs[0].silent);
  EXPECT_TRUE(r.inputs[1].silent);
  EXPECT_TRUE(r.silent);
  EXPECT_NEAR(r.max_age_s, 3.0, 1e-9);
  EXPECT_EQ(r.description, "input silent: CBLOX_FRAME_POSE for 3.0 s");
  ASSERT_EQ(f.lines.size(), 1u);
  EXPECT_EQ(f.lines[0],
            "cblox-mapper: input silent: nothing on CBLOX_FRAME_POSE for 3.0 s (limit 2.0 s)");

  f.advance(2000);  // now both
  EXPECT_EQ(watch.check().description,
            "input silent: CBLOX_DEPTH for 2.0 s, CBLOX_FRAME_POSE for 5.0 s");
  EXPECT_EQ(f.lines.size(), 2u);
}

TEST(InputWatchTest, ZeroTurnsSilenceOffButAgesAreReported) {
  Fixture f;
  InputWatch watch("cblox-test", 0.0, f.sink(), f.clock());
  watch.watch("A");
  f.advance(60000);
  const InputWatch::Report r = watch.check();
  EXPECT_FALSE(r.silent);
  EXPECT_NEAR(r.max_age_s, 60.0, 1e-9);
  watch.arrived("A");
  EXPECT_TRUE(f.lines.empty());
  HeartbeatBuilder hb("cblox-test", "running");
  watch.addTo(&hb);
  const heartbeat_t msg = hb.build();
  EXPECT_EQ(msg.state, "running");
  EXPECT_EQ(counters(msg).at("input_silent"), 0);
  EXPECT_EQ(counters(msg).at("input_age_ms"), 0);
}

TEST(InputWatchTest, HeartbeatCountersAndStatePrefix) {
  Fixture f;
  InputWatch watch("cblox-test", 2.0, f.sink(), f.clock());
  watch.watch("CBLOX_DEPTH");
  watch.arrived("CBLOX_DEPTH");
  f.advance(1234);
  {
    HeartbeatBuilder hb("cblox-test", "running");
    watch.addTo(&hb);
    const heartbeat_t msg = hb.build();
    EXPECT_EQ(msg.state, "running");
    const auto c = counters(msg);
    EXPECT_EQ(c.at("input_silent"), 0);
    EXPECT_EQ(c.at("input_age_ms"), 1234);
    EXPECT_EQ(c.at("input_silences"), 0);
  }
  f.advance(4000);
  {
    HeartbeatBuilder hb("cblox-test", "running");
    watch.addTo(&hb);
    EXPECT_EQ(hb.state(), "input silent: CBLOX_DEPTH for 5.2 s; running");
    const heartbeat_t msg = hb.build();
    EXPECT_EQ(msg.state, "input silent: CBLOX_DEPTH for 5.2 s; running");
    const auto c = counters(msg);
    EXPECT_EQ(c.at("input_silent"), 1);
    EXPECT_EQ(c.at("input_age_ms"), 5234);
    EXPECT_EQ(c.at("input_silences"), 1);
    EXPECT_EQ(c.count("cpu_ms"), 1u);  // the builder's own counters still follow
  }
  {
    HeartbeatBuilder hb("cblox-test", "");
    watch.addTo(&hb);
    EXPECT_EQ(hb.build().state, "input silent: CBLOX_DEPTH for 5.2 s");
  }
  EXPECT_EQ(f.lines.size(), 1u);  // addTo checks; the silence was logged once
}

// A stopping process no longer waits for input: its last heartbeat says "stopped" alone.
TEST(InputWatchTest, StopWatchingEndsTheSilenceReportButKeepsTheAges) {
  Fixture f;
  InputWatch watch("cblox-test", 2.0, f.sink(), f.clock());
  watch.watch("CBLOX_DEPTH");
  watch.arrived("CBLOX_DEPTH");
  f.advance(3000);
  EXPECT_TRUE(watch.check().silent);
  watch.stopWatching();
  f.advance(1000);
  HeartbeatBuilder hb("cblox-test", "stopped");
  watch.addTo(&hb);
  const heartbeat_t msg = hb.build();
  EXPECT_EQ(msg.state, "stopped");
  EXPECT_EQ(counters(msg).at("input_silent"), 0);
  EXPECT_EQ(counters(msg).at("input_age_ms"), 4000);
  EXPECT_EQ(counters(msg).at("input_silences"), 1);
  EXPECT_EQ(f.lines.size(), 1u);  // the silence, logged once; no "input back"
}

TEST(InputWatchTest, NothingAddedWithoutInputsAndBadLimitsRefused) {
  Fixture f;
  InputWatch watch("cblox-test", 2.0, f.sink(), f.clock());
  HeartbeatBuilder hb("cblox-test", "running");
  watch.addTo(&hb);
  const heartbeat_t msg = hb.build();
  EXPECT_EQ(msg.num_counters, 2);  // cpu_ms, rss_kib only
  EXPECT_EQ(msg.state, "running");

  for (const double bad :
       {-1.0, std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity()}) {
    EXPECT_THROW(InputWatch("x", bad), std::invalid_argument) << bad;
    EXPECT_NE(validateInputSilence(bad).find("input_silence_s"), std::string::npos);
  }
  EXPECT_EQ(validateInputSilence(0.0), "");
  EXPECT_EQ(validateInputSilence(2.5), "");
}

// ---------------------------------------------------------------------------------------
// MessageGuard -> InputWatch, over LCM's in-process provider.

heartbeat_t someHeartbeat() {
  heartbeat_t hb;
  hb.utime = 1;
  hb.process = "other";
  hb.pid = 7;
  hb.state = "x";
  hb.num_counters = 0;
  return hb;
}

TEST(InputWatchTest, MessageGuardRecordsOnlyCheckedMessagesOnWatchedChannels) {
  lcm::LCM lcm("memq://");
  ASSERT_TRUE(lcm.good());
  Fixture f;
  InputWatch watch("cblox-test", 2.0, f.sink(), f.clock());
  watch.watch("WATCHED");
  std::vector<std::string> guard_lines;
  MessageGuard guard(&lcm, [&](const std::string& line) { guard_lines.push_back(line); });
  guard.setInputWatch(&watch);
  int handled = 0;
  bool throw_in_handler = false;
  const auto handler = [&](const heartbeat_t&, const std::string&) {
    ++handled;
    if (throw_in_handler) throw std::runtime_error("handler failed");
  };
  guard.subscribe<heartbeat_t>("WATCHED", handler);
  guard.subscribe<heartbeat_t>("OTHER", handler);
  const auto deliver = [&] {
    while (lcm.handleTimeout(0) > 0) {
    }
  };

  f.advance(3000);
  ASSERT_TRUE(watch.check().silent);
  ASSERT_EQ(f.lines.size(), 1u);

  // Bytes that fail the wire check are no input; a message on another channel neither.
  const uint8_t garbage[] = {1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12};
  lcm.publish("WATCHED", garbage, sizeof(garbage));
  const heartbeat_t valid = someHeartbeat();
  lcm.publish("OTHER", &valid);
  deliver();
  EXPECT_EQ(handled, 1);
  EXPECT_EQ(guard.counts().refusedTotal(), 1u);
  EXPECT_TRUE(watch.check().silent);
  EXPECT_EQ(f.lines.size(), 1u);

  // A valid message ends the silence.
  f.advance(500);
  lcm.publish("WATCHED", &valid);
  deliver();
  EXPECT_EQ(handled, 2);
  ASSERT_EQ(f.lines.size(), 2u);
  EXPECT_EQ(f.lines[1], "cblox-test: input back: WATCHED after 3.5 s of silence");
  EXPECT_FALSE(watch.check().silent);

  // A message whose handler throws did arrive.
  f.advance(2500);
  ASSERT_TRUE(watch.check().silent);
  throw_in_handler = true;
  lcm.publish("WATCHED", &valid);
  deliver();
  EXPECT_EQ(guard.counts().handler_errors, 1u);
  EXPECT_FALSE(watch.check().silent);
  EXPECT_EQ(f.lines.size(), 4u);  // silent again, back again

  // The guard's heartbeat part carries the watch's counters and state.
  f.advance(2100);
  HeartbeatBuilder hb("cblox-test", "running");
  guard.addTo(&hb);
  const heartbeat_t msg = hb.build();
  const auto c = counters(msg);
  EXPECT_EQ(c.at("input_silent"), 1);
  EXPECT_EQ(c.at("input_age_ms"), 2100);
  EXPECT_EQ(c.at("input_silences"), 3);
  EXPECT_EQ(c.at("handler_errors"), 1);
  EXPECT_EQ(msg.state, "input silent: WATCHED for 2.1 s; running");
}

}  // namespace
}  // namespace cblox
