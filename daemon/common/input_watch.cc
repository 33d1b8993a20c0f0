#include "daemon/common/input_watch.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace cblox {
namespace {

double seconds(InputWatch::Clock::duration d) { return std::chrono::duration<double>(d).count(); }

std::string formatSeconds(double s) {
  char text[32];
  std::snprintf(text, sizeof(text), "%.1f s", s);
  return text;
}

}  // namespace

InputWatch::InputWatch(std::string process, double silence_s, LogSink log, NowFn now)
    : process_(std::move(process)),
      silence_s_(silence_s),
      log_(log ? std::move(log) : LogSink([](const std::string& line) {
        std::fprintf(stderr, "%s\n", line.c_str());
        std::fflush(stderr);
      })),
      now_(now ? std::move(now) : NowFn([] { return Clock::now(); })) {
  if (const std::string e = validateInputSilence(silence_s); !e.empty()) {
    throw std::invalid_argument(e);
  }
}

void InputWatch::watch(const std::string& input) {
  const Clock::time_point now = now_();
  std::lock_guard<std::mutex> lock(mutex_);
  for (const Entry& e : entries_) {
    if (e.name == input) return;
  }
  entries_.push_back(Entry{input, now, false, false});
}

bool InputWatch::watches(const std::string& input) const {
  std::lock_guard<std::mutex> lock(mutex_);
  return std::any_of(entries_.begin(), entries_.end(),
                     [&](const Entry& e) { return e.name == input; });
}

void InputWatch::arrived(const std::string& input) {
  const Clock::time_point now = now_();
  std::vector<std::string> lines;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    for (Entry& e : entries_) {
      if (e.name != input) continue;
      const double gap_s = seconds(now - e.last);
      if (e.silent) {
        lines.push_back(process_ + ": input back: " + e.name + " after " + formatSeconds(gap_s) +
                        " of silence");
      } else if (silence_s_ > 0.0 && gap_s >= silence_s_) {
        // A silence no check() saw (shorter than the check period beyond the limit).
        ++silences_;
        lines.push_back(process_ + ": input silent and back: nothing on " + e.name + " for " +
                        formatSeconds(gap_s) + " (limit " + formatSeconds(silence_s_) + ")");
      }
      e.last = now;
      e.heard = true;
      e.silent = false;
      break;
    }
  }
  log(lines);
}

InputWatch::Report InputWatch::check() {
  const Clock::time_point now = now_();
  Report report;
  std::vector<std::string> lines;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    for (Entry& e : entries_) {
      Input input;
      input.name = e.name;
      input.age_s = std::max(0.0, seconds(now - e.last));
      input.heard = e.heard;
      input.silent = !stopped_ && silence_s_ > 0.0 && input.age_s >= silence_s_;
      if (input.silent && !e.silent) {
        ++silences_;
        lines.push_back(process_ + ": input silent: nothing on " + e.name +
                        (e.heard ? " for " : " since start, ") + formatSeconds(input.age_s) +
                        (e.heard ? "" : " ago") + " (limit " + formatSeconds(silence_s_) + ")");
      }
      e.silent = input.silent;
      report.max_age_s = std::max(report.max_age_s, input.age_s);
      if (input.silent) {
        report.silent = true;
        report.description += (report.description.empty() ? "input silent: " : ", ") + e.name +
                              " for " + formatSeconds(input.age_s) + (e.heard ? "" : " (none yet)");
      }
      report.inputs.push_back(std::move(input));
    }
    report.silences = silences_;
  }
  log(lines);
  return report;
}

void InputWatch::stopWatching() {
  std::lock_guard<std::mutex> lock(mutex_);
  stopped_ = true;
}

void InputWatch::addTo(HeartbeatBuilder* heartbeat) {
  const Report report = check();
  if (report.inputs.empty()) return;
  heartbeat->add("input_silent", static_cast<int64_t>(report.silent ? 1 : 0));
  heartbeat->add("input_age_ms", static_cast<int64_t>(std::llround(report.max_age_s * 1000.0)));
  heartbeat->add("input_silences", report.silences);
  if (report.silent) {
    const std::string& state = heartbeat->state();
    heartbeat->setState(state.empty() ? report.description : report.description + "; " + state);
  }
}

void InputWatch::log(const std::vector<std::string>& lines) const {
  for (const std::string& line : lines) log_(line);
}

}  // namespace cblox
