#include "daemon/replay/log_replayer.h"

#include <sys/types.h>

#include <chrono>
#include <cstdio>
#include <cstring>
#include <deque>
#include <future>
#include <limits>
#include <optional>
#include <stdexcept>
#include <utility>

#include <cblox/depth_frame_t.hpp>
#include <cblox/frame_pose_t.hpp>
#include <cblox/keyframe_pose_batch_t.hpp>
#include <cblox/keyframe_t.hpp>
#include <cblox/pose_stamped_t.hpp>
#include <cblox/stereo_pair_t.hpp>
#include <lcm/lcm-cpp.hpp>

#include "core/common/text_format.h"
#include "daemon/common/lcm_messages.h"
#include "daemon/common/message_guard.h"
#include "daemon/mapper/mapper_lcm_node.h"
#include "daemon/tracker/tracker_lcm_node.h"
#include "lcmtypes/wire_check.h"

namespace cblox {
namespace {

using Clock = std::chrono::steady_clock;

// How long one input may keep a thread busy before the replay gives up (a hang, not work).
constexpr std::chrono::milliseconds kSettleTimeout = std::chrono::minutes(10);
// Maintenance rounds after the log's end at the most (each asks at least one more pair).
constexpr int kMaxEndRounds = 100;

// One log event kept for later.
struct HeldEvent {
  std::string channel;
  std::vector<uint8_t> data;
  int64_t utime = 0;
};

// The utime (first member of every cblox sensor message) of an encoded Msg that passes the
// wire check; nullopt when it does not (the subscriber's guard will count it).
template <typename Msg>
std::optional<int64_t> checkedUtime(const void* data, size_t size) {
  if (!checkWire(data, size, Msg::getTypeName(), Msg::getHash()).ok()) return std::nullopt;
  const auto* b = static_cast<const uint8_t*>(data) + 8;
  uint64_t v = 0;
  for (int i = 0; i < 8; ++i) v = (v << 8) | b[i];
  return static_cast<int64_t>(v);
}

// LCM log events (lcm/eventlog.c): sync word 0xEDA1DA01, event number (8 bytes), time stamp
// (8), channel length (4), data length (4), all big-endian, then the channel and the data.
constexpr uint8_t kLogSync[4] = {0xED, 0xA1, 0xDA, 0x01};
constexpr off_t kLogHeaderBytes = 28;
constexpr int32_t kMaxChannelBytes = 1000;  // LCM's own bound (eventlog.c)

uint32_t bigEndian32(const uint8_t* b) {
  return (uint32_t{b[0]} << 24) | (uint32_t{b[1]} << 16) | (uint32_t{b[2]} << 8) | b[3];
}

// Whether a whole event with a sane header starts at `at`: the sync word, a channel length
// in (0, 1000) and payloads that end within the file. Leaves the file at `at`.
bool logEventFits(FILE* file, off_t at, off_t file_size) {
  uint8_t h[kLogHeaderBytes];
  const bool read =
      ::fseeko(file, at, SEEK_SET) == 0 && std::fread(h, 1, sizeof(h), file) == sizeof(h);
  ::fseeko(file, at, SEEK_SET);
  if (!read || std::memcmp(h, kLogSync, 4) != 0) return false;
  const auto channel_len = static_cast<int32_t>(bigEndian32(h + 20));
  const auto data_len = static_cast<int32_t>(bigEndian32(h + 24));
  if (channel_len <= 0 || channel_len >= kMaxChannelBytes || data_len < 0) return false;
  return kLogHeaderBytes + channel_len + static_cast<off_t>(data_len) <= file_size - at;
}

// The position of the next sync word at or after `from`, or -1. Reads each byte once.
off_t findLogSync(FILE* file, off_t from, off_t file_size) {
  std::vector<uint8_t> buffer(1 << 16);
  off_t base = from;
  while (base < file_size) {
    if (::fseeko(file, base, SEEK_SET) != 0) return -1;
    const size_t n = std::fread(buffer.data(), 1, buffer.size(), file);
    if (n < 4) return -1;
    for (size_t i = 0; i + 4 <= n; ++i) {
      if (std::memcmp(buffer.data() + i, kLogSync, 4) == 0) return base + static_cast<off_t>(i);
    }
    base += static_cast<off_t>(n - 3);  // a sync word may straddle two reads
  }
  return -1;
}

}  // namespace

ReplayConfig deterministicReplayConfig(ReplayConfig config) {
  config.mapper.mapper.integrator.max_integration_time_s = 0.0;
  config.mapper.mapper.maintenance_clock = MaintenanceClock::kInput;
  // A depth frame is handed over once its pose is there; one without a pose then never gets
  // one, so it is refused at once instead of after a wall-clock wait.
  config.mapper.mapper.max_pose_wait_s = 0.0;
  config.tracker.tracker.covariance.max_linearization_age_s = 0.0;
  config.tracker.tracker.covariance.min_linearization_interval_s = 0.0;  // no wall-clock wait
  // The mapper reads depth on a channel of its own, so that in RGB-D mode (one channel for
  // both) it gets each frame after the tracker's pose of it.
  config.mapper.depth_channel = "CBLOX_REPLAY/" + config.mapper.depth_channel;
  return config;
}

struct LogReplayer::Impl {
  explicit Impl(const ReplayConfig& c) : config(c), lcm("memq://"), outputs_guard(&lcm) {}

  bool trackerMode() const { return config.mapper.mapper.pose_source == PoseSource::kTracker; }

  // Delivers every message on the bus; the number delivered.
  int drain() {
    int n = 0;
    while (lcm.handleTimeout(0) > 0) ++n;
    return n;
  }

  // Until nothing is queued on the bus and no thread has work: deliver, wait, repeat.
  void settle() {
    drain();
    while (true) {
      if (tracker && !tracker->waitUntilSettled(kSettleTimeout)) {
        throw std::runtime_error("the tracker did not finish a frame within 10 minutes");
      }
      if (!mapper->waitUntilIdle(kSettleTimeout)) {
        throw std::runtime_error("the mapper did not become idle within 10 minutes");
      }
      if (drain() == 0) return;
    }
  }

  void publish(const std::string& channel, const void* data, size_t size) {
    lcm.publish(channel, data, static_cast<unsigned int>(size));
  }

  // The held tracker frame to the tracker; then the depth frames its pose serves.
  void releaseTrackerFrame() {
    if (!held_frame) return;
    publish(held_frame->channel, held_frame->data.data(), held_frame->data.size());
    ++summary.tracker_frames;
    settle();
    horizon = std::max(horizon, held_frame->utime);
    held_frame.reset();
    releaseDepth();
  }

  // Deferred depth frames at or before the pose horizon to the mapper, one at a time.
  void releaseDepth() {
    while (!deferred_depth.empty() && deferred_depth.front().utime <= horizon) {
      const HeldEvent& e = deferred_depth.front();
      publish(config.mapper.depth_channel, e.data.data(), e.data.size());
      ++summary.depth_frames;
      settle();
      deferred_depth.pop_front();
    }
  }

  void onEvent(const lcm::LogEvent& event) {
    const std::string& channel = event.channel;
    const void* data = event.data;
    const size_t size = static_cast<size_t>(event.datalen);
    bool used = false;
    const std::string& tracker_frame_channel = config.tracker.tracker.mode == TrackerMode::kStereo
                                                   ? config.tracker.stereo_channel
                                                   : config.tracker.depth_channel;
    if (trackerMode() && channel == tracker_frame_channel) {
      used = true;
      releaseTrackerFrame();
      const std::optional<int64_t> utime = config.tracker.tracker.mode == TrackerMode::kStereo
                                               ? checkedUtime<stereo_pair_t>(data, size)
                                               : checkedUtime<depth_frame_t>(data, size);
      if (utime) {
        const auto* bytes = static_cast<const uint8_t*>(data);
        held_frame = HeldEvent{channel, std::vector<uint8_t>(bytes, bytes + size), *utime};
      } else {
        publish(channel, data, size);  // refused and counted by the tracker's guard
        ++summary.tracker_frames;
        settle();
      }
    }
    if (channel == original_depth_channel) {
      used = true;
      const std::optional<int64_t> utime = checkedUtime<depth_frame_t>(data, size);
      if (utime) {
        const auto* bytes = static_cast<const uint8_t*>(data);
        deferred_depth.push_back(
            HeldEvent{channel, std::vector<uint8_t>(bytes, bytes + size), *utime});
        releaseDepth();
      } else {
        publish(config.mapper.depth_channel, data, size);  // refused by the mapper's guard
        ++summary.depth_frames;
        settle();
      }
    }
    const bool tracker_wants_gt =
        trackerMode() && config.tracker.tracker.initial_pose == InitialPose::kGroundTruth;
    const bool mapper_wants_gt = !trackerMode();
    if ((tracker_wants_gt && channel == config.tracker.ground_truth_channel) ||
        (mapper_wants_gt && channel == config.mapper.ground_truth_channel)) {
      used = true;
      publish(channel, data, size);
      ++summary.ground_truth_poses;
      drain();  // the handlers only store the pose
      if (mapper_wants_gt) {
        if (const std::optional<int64_t> utime = checkedUtime<pose_stamped_t>(data, size)) {
          horizon = std::max(horizon, *utime);
          releaseDepth();
        }
      }
    }
    if (!used) ++summary.ignored[channel];
  }

  // `stopped`: the replay was stopped; maintenance is not ticked after the last input.
  void finish(bool stopped) {
    releaseTrackerFrame();
    horizon = std::numeric_limits<int64_t>::max();
    releaseDepth();
    settle();
    // The log is over but maintenance is not: a live mapper's 0.25 s tick asks the pairs
    // freed after the last input (the input clock does not); ticks until one changes nothing.
    for (int round = 0; !stopped && round < kMaxEndRounds; ++round) {
      const uint64_t before = mapper->status().fusion.progress();
      mapper->maintenanceTick();
      settle();
      if (mapper->status().fusion.progress() == before) break;
    }
  }

  void subscribeOutputs() {
    outputs_guard.subscribe<frame_pose_t>(
        config.tracker.frame_pose_channel, [this](const frame_pose_t& m, const std::string&) {
          if (m.tracking_state == frame_pose_t::NOT_INITIALIZED ||
              m.tracking_state == frame_pose_t::LOST) {
            return;
          }
          if (std::optional<Transformationd> T = fromPoseMsg(m.T_G_C, nullptr)) {
            summary.frame_poses.push_back(ReplayPose{m.utime, m.frame_id, *T});
          }
        });
    outputs_guard.subscribe<keyframe_t>(
        config.tracker.keyframe_channel, [this](const keyframe_t& m, const std::string&) {
          if (std::optional<Transformationd> T = fromPoseMsg(m.T_G_K, nullptr)) {
            keyframes[{m.map_epoch, m.keyframe_id}] = ReplayPose{m.utime, m.keyframe_id, *T};
          }
        });
    outputs_guard.subscribe<keyframe_pose_batch_t>(
        config.tracker.keyframe_poses_channel,
        [this](const keyframe_pose_batch_t& m, const std::string&) {
          for (size_t i = 0; i < m.keyframe_ids.size() && i < m.poses.size(); ++i) {
            auto it = keyframes.find({m.map_epoch, m.keyframe_ids[i]});
            if (it == keyframes.end()) continue;
            if (std::optional<Transformationd> T = fromPoseMsg(m.poses[i], nullptr)) {
              it->second.T_G_C = *T;
            }
          }
        });
  }

  ReplayConfig config;
  std::string original_depth_channel;
  lcm::LCM lcm;
  std::unique_ptr<TrackerLcmNode> tracker_lcm;
  std::unique_ptr<TrackerNode> tracker;
  std::unique_ptr<Mapper> mapper;
  std::unique_ptr<MapperNode> mapper_node;
  MessageGuard outputs_guard;

  std::optional<HeldEvent> held_frame;
  std::deque<HeldEvent> deferred_depth;
  int64_t horizon = std::numeric_limits<int64_t>::min();        // the mapper has poses up to here
  std::map<std::pair<int32_t, int64_t>, ReplayPose> keyframes;  // by (map epoch, id)
  ReplaySummary summary;
  bool ran = false;
};

LogReplayer::LogReplayer(ReplayConfig config, const BinaryVocabulary* vocabulary)
    : config_(deterministicReplayConfig(config)), impl_(std::make_unique<Impl>(config_)) {
  if (!impl_->lcm.good()) throw std::runtime_error("cannot open the in-process LCM (memq://)");
  impl_->original_depth_channel = config.mapper.depth_channel;
  if (const std::string e = config_.mapper.validate(); !e.empty()) {
    throw std::invalid_argument("mapper: " + e);
  }
  impl_->mapper = std::make_unique<Mapper>(config_.mapper.mapper);
  impl_->mapper_node =
      std::make_unique<MapperNode>(impl_->config.mapper, &impl_->lcm, impl_->mapper.get());
  if (impl_->trackerMode()) {
    if (const std::string e = config_.tracker.validate(); !e.empty()) {
      throw std::invalid_argument("tracker: " + e);
    }
    impl_->tracker_lcm = std::make_unique<TrackerLcmNode>(impl_->config.tracker, &impl_->lcm);
    impl_->tracker = std::make_unique<TrackerNode>(impl_->config.tracker.tracker, vocabulary,
                                                   impl_->tracker_lcm->outputs());
    impl_->tracker_lcm->subscribe(impl_->tracker.get());
    impl_->subscribeOutputs();
  }
  impl_->mapper_node->subscribe();  // sets the covariance requester: before start()
}

LogReplayer::~LogReplayer() {
  if (impl_->tracker) impl_->tracker->stop();
  impl_->mapper->stop();
}

ReplaySummary LogReplayer::run(const std::function<void(const ReplayProgress&)>& progress,
                               double progress_period_s, const std::atomic<bool>* stop) {
  if (impl_->ran) throw std::logic_error("LogReplayer::run called twice");
  impl_->ran = true;
  lcm::LogFile log(config_.log_path, "r");
  if (!log.good()) throw std::runtime_error("cannot open the log " + config_.log_path);
  FILE* file = log.getFilePtr();
  off_t file_size = 0;
  if (::fseeko(file, 0, SEEK_END) == 0) file_size = ::ftello(file);
  ::fseeko(file, 0, SEEK_SET);

  std::string error;
  if (!impl_->mapper->start(&error)) throw std::runtime_error(error);
  if (impl_->tracker) impl_->tracker->start();

  ReplaySummary& summary = impl_->summary;
  const Clock::time_point start = Clock::now();
  Clock::time_point last_progress = start;
  int64_t first_event_us = 0, last_event_us = 0;
  const auto report = [&] {
    if (!progress) return;
    ReplayProgress p;
    p.events = summary.events;
    p.frames = impl_->trackerMode() ? summary.tracker_frames : summary.depth_frames;
    const off_t at = ::ftello(file);
    p.fraction = file_size > 0 && at >= 0
                     ? std::min(1.0, static_cast<double>(at) / static_cast<double>(file_size))
                     : 0.0;
    p.elapsed_s = secondsSince(start);
    p.log_elapsed_s = static_cast<double>(last_event_us - first_event_us) * 1e-6;
    progress(p);
  };

  // Start of bytes that did not read as an event (damaged or cut short), while skipping;
  // -1 when not skipping.
  off_t skipping_from = -1;
  const auto skipDamage = [&](off_t at) {
    if (skipping_from < 0) {
      skipping_from = at;
      ++summary.damaged_regions;
    }
    const off_t next = findLogSync(file, at + 1, file_size);
    if (next < 0) return false;
    return ::fseeko(file, next, SEEK_SET) == 0;
  };
  while (!(stop != nullptr && stop->load())) {
    const off_t at = ::ftello(file);
    if (at < 0 || at >= file_size) break;
    // LCM's reader allocates what an event's header says: bound it by the bytes left first.
    const lcm::LogEvent* event = logEventFits(file, at, file_size) ? log.readNextEvent() : nullptr;
    if (event == nullptr) {
      if (!skipDamage(at)) break;
      continue;
    }
    if (skipping_from >= 0) {
      summary.skipped_bytes += static_cast<uint64_t>(at - skipping_from);
      skipping_from = -1;
    }
    if (summary.events == 0) first_event_us = event->timestamp;
    last_event_us = event->timestamp;
    ++summary.events;
    impl_->onEvent(*event);
    if (secondsSince(last_progress) >= progress_period_s) {
      last_progress = Clock::now();
      report();
    }
  }
  if (skipping_from >= 0) {
    summary.skipped_bytes += static_cast<uint64_t>(file_size - skipping_from);
  }
  summary.stopped = stop != nullptr && stop->load();
  impl_->finish(summary.stopped);
  summary.wall_s = secondsSince(start);
  summary.log_span_s = static_cast<double>(last_event_us - first_event_us) * 1e-6;
  report();
  for (const auto& [id, pose] : impl_->keyframes) summary.keyframes.push_back(pose);
  for (const MessageGuardCounts& counts :
       {impl_->mapper_node->messageCounts(),
        impl_->tracker_lcm ? impl_->tracker_lcm->messageCounts() : MessageGuardCounts{}}) {
    for (size_t kind = 0; kind < counts.refused.size(); ++kind) {
      if (counts.refused[kind] > 0) {
        summary.refused[wireErrorName(static_cast<WireError>(kind))] += counts.refused[kind];
      }
    }
    summary.handler_errors += counts.handler_errors;
  }
  if (impl_->tracker) summary.tracker = impl_->tracker->status();
  summary.mapper = impl_->mapper->status();
  return summary;
}

MapperReply LogReplayer::command(const MapperCommand& command) {
  std::promise<MapperReply> promise;
  std::future<MapperReply> reply = promise.get_future();
  impl_->mapper->onCommand(command, [&promise](const MapperReply& r) { promise.set_value(r); });
  return reply.get();
}

}  // namespace cblox
