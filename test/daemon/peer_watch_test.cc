// PeerWatch: a second instance of a process on the bus, with an injected clock.

#include "daemon/common/peer_watch.h"

#include <chrono>
#include <string>
#include <vector>

#include <gtest/gtest.h>

namespace cblox {
namespace {

using Clock = PeerWatch::Clock;

struct Fixture {
  Clock::time_point now{};
  std::vector<std::string> lines;
  PeerWatch watch{"cblox-mapper", 100, 5.0, [this](const std::string& l) { lines.push_back(l); },
                  [this] { return now; }};
  void advance(double s) {
    now += std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(s));
  }
};

TEST(PeerWatchTest, OnlyAnotherPidUnderTheSameNameIsAPeer) {
  Fixture f;
  f.watch.onHeartbeat("cblox-mapper", 100);   // itself (LCM loops its own messages back)
  f.watch.onHeartbeat("cblox-tracker", 200);  // another process
  EXPECT_TRUE(f.watch.peers().empty());
  EXPECT_EQ(f.watch.peersSeen(), 0u);
  EXPECT_TRUE(f.lines.empty());
}

TEST(PeerWatchTest, LogsOnceWhenAPeerAppearsAndOnceWhenItIsGone) {
  Fixture f;
  f.watch.onHeartbeat("cblox-mapper", 4242);
  f.advance(1.0);
  f.watch.onHeartbeat("cblox-mapper", 4242);
  ASSERT_EQ(f.lines.size(), 1u);
  EXPECT_EQ(f.lines[0].rfind("cblox-mapper: another cblox-mapper (pid 4242) is on this bus", 0),
            0u)
      << f.lines[0];
  f.advance(4.999);
  EXPECT_EQ(f.watch.peers(), std::vector<int32_t>{4242});  // heard 4.999 s ago
  HeartbeatBuilder hb("cblox-mapper", "running");
  f.watch.addTo(&hb);
  const heartbeat_t msg = hb.build();
  EXPECT_EQ(msg.state, "another cblox-mapper on this bus (pid 4242); running");
  ASSERT_GE(msg.counter_names.size(), 2u);
  EXPECT_EQ(msg.counter_names[0], "other_instances");
  EXPECT_EQ(msg.counter_values[0], 1);
  EXPECT_EQ(msg.counter_names[1], "other_instances_seen");
  EXPECT_EQ(msg.counter_values[1], 1);
  f.advance(0.001);  // 5 s without a heartbeat: gone
  EXPECT_TRUE(f.watch.peers().empty());
  ASSERT_EQ(f.lines.size(), 2u);
  EXPECT_EQ(f.lines[1], "cblox-mapper: the other cblox-mapper (pid 4242) is gone");
  HeartbeatBuilder after("cblox-mapper", "running");
  f.watch.addTo(&after);
  const heartbeat_t later = after.build();
  EXPECT_EQ(later.state, "running");
  EXPECT_EQ(later.counter_values[0], 0);
  EXPECT_EQ(later.counter_values[1], 1);  // seen since start
}

}  // namespace
}  // namespace cblox
