#pragma once

// Input-silence health: a process that stops hearing its input says so. InputWatch keeps the
// last arrival time of each watched input (an LCM channel, or capture's frame source); an
// input with nothing for input_silence_s is *silent*. The watch logs one line when an input
// falls silent and one when it comes back, and adds to the heartbeat:
//   input_silent    1 while any watched input is silent, else 0
//   input_age_ms    time since the last arrival of the input heard longest ago (since the
//                   watch began for an input never heard)
//   input_silences  silences since start (each begins when an input is found silent)
// and, while an input is silent, puts "input silent: CBLOX_DEPTH for 5.2 s" (several inputs
// separated by ", ", "(none yet)" after one never heard) before the process's own state:
//   "input silent: CBLOX_DEPTH for 5.2 s; running".
// The daemons feed it from MessageGuard (MessageGuard::setInputWatch: every message that
// passes the wire check on a watched channel) and cblox-capture from its frame loop.

#include <chrono>
#include <cstdint>
#include <functional>
#include <mutex>
#include <string>
#include <vector>

#include "daemon/common/heartbeat.h"
#include "daemon/common/input_silence.h"

namespace cblox {

/// Thread-safety: every member function is thread-safe (one mutex; log lines are written
/// after it is released). arrived() is cheap (a lookup in the few watched inputs).
class InputWatch {
 public:
  using Clock = std::chrono::steady_clock;
  using NowFn = std::function<Clock::time_point()>;
  using LogSink = std::function<void(const std::string&)>;

  /// One watched input as check() saw it.
  struct Input {
    std::string name;
    double age_s = 0.0;  ///< since its last arrival (since watch() if never heard)
    bool heard = false;  ///< at least one arrival
    bool silent = false;
  };
  /// What check() found.
  struct Report {
    bool silent = false;        ///< any input silent
    double max_age_s = 0.0;     ///< the largest age over the inputs (0 without inputs)
    uint64_t silences = 0;      ///< silences begun since start
    std::vector<Input> inputs;  ///< in the order watch() was called
    /// "input silent: CBLOX_DEPTH for 5.2 s, CBLOX_GT_POSE for 3.0 s (none yet)", or empty
    /// when nothing is silent.
    std::string description;
  };

  /// `process` starts the log lines ("cblox-mapper: input silent: ..."). An input is silent
  /// once nothing arrived for `silence_s` seconds (age >= silence_s); 0 turns silence off
  /// (ages are still reported). `log` receives the lines (default: stderr); `now` is the
  /// clock (default: steady_clock::now; tests inject their own). Throws
  /// std::invalid_argument when validateInputSilence(silence_s) fails.
  InputWatch(std::string process, double silence_s, LogSink log = nullptr, NowFn now = nullptr);
  InputWatch(const InputWatch&) = delete;
  InputWatch& operator=(const InputWatch&) = delete;

  double silenceSeconds() const { return silence_s_; }

  /// Starts watching `input` (a channel name, or e.g. "source sim:room"); its age counts
  /// from now until its first arrival. Watching a name twice does nothing.
  void watch(const std::string& input);
  bool watches(const std::string& input) const;

  /// One arrival on `input` now (other names are ignored). If the input was silent, logs
  /// "<process>: input back: <input> after 5.3 s of silence". A silence that lasted silence_s
  /// or more but ended before any check() saw it is counted and logged here in one line
  /// ("<process>: input silent and back: nothing on <input> for 2.4 s (limit 2.0 s)"), so
  /// every silence is counted and logged once.
  void arrived(const std::string& input);

  /// Evaluates the inputs now; logs "<process>: input silent: nothing on <input> for 2.0 s
  /// (limit 2.0 s)" ("since start" for an input never heard) for each input that became
  /// silent since the last check.
  Report check();

  /// The process no longer waits for input (it is stopping): from now on no input is
  /// silent (ages are still reported), so its last heartbeat says "stopped", not "input
  /// silent". Irreversible.
  void stopWatching();

  /// check(), then adds input_silent, input_age_ms and input_silences to `heartbeat` and, if
  /// an input is silent, prefixes its state with the description and "; " (or sets it to the
  /// description when the state is empty). Nothing is added without watched inputs.
  void addTo(HeartbeatBuilder* heartbeat);

 private:
  struct Entry {
    std::string name;
    Clock::time_point last;  // last arrival, or when watching began
    bool heard = false;
    bool silent = false;  // check() reported the silence (and "input back" is due)
  };
  void log(const std::vector<std::string>& lines) const;

  const std::string process_;
  const double silence_s_;
  const LogSink log_;
  const NowFn now_;
  bool stopped_ = false;  // guarded by mutex_
  mutable std::mutex mutex_;
  std::vector<Entry> entries_;
  uint64_t silences_ = 0;
};

}  // namespace cblox
