#include "daemon/common/heartbeat.h"

#include <unistd.h>

#include <cmath>
#include <fstream>
#include <limits>
#include <sstream>

#include "daemon/common/run_loop.h"

namespace cblox {

ProcessUsage ProcessUsage::current() {
  ProcessUsage usage;
  const long ticks_per_s = ::sysconf(_SC_CLK_TCK);
  const long page_size = ::sysconf(_SC_PAGESIZE);
  std::ifstream stat("/proc/self/stat");
  std::string line;
  if (ticks_per_s > 0 && std::getline(stat, line)) {
    // Fields after the command name (which may hold spaces and parentheses): the last ')'
    // ends it; utime and stime are fields 14 and 15 of the whole line.
    const size_t end = line.rfind(')');
    if (end != std::string::npos) {
      std::istringstream rest(line.substr(end + 1));
      std::string field;
      long long utime = 0, stime = 0;
      for (int i = 3; i <= 15 && rest >> field; ++i) {
        if (i == 14) utime = std::atoll(field.c_str());
        if (i == 15) stime = std::atoll(field.c_str());
      }
      usage.cpu_ms = (utime + stime) * 1000 / ticks_per_s;
    }
  }
  std::ifstream statm("/proc/self/statm");
  long long pages_total = 0, pages_resident = 0;
  if (page_size > 0 && statm >> pages_total >> pages_resident) {
    usage.rss_kib = pages_resident * (page_size / 1024);
  }
  return usage;
}

HeartbeatBuilder::HeartbeatBuilder(std::string process, std::string state) {
  msg_.process = std::move(process);
  msg_.state = std::move(state);
  msg_.num_counters = 0;
}

HeartbeatBuilder& HeartbeatBuilder::add(const std::string& name, int64_t value) {
  msg_.counter_names.push_back(name);
  msg_.counter_values.push_back(value);
  msg_.num_counters = static_cast<int32_t>(msg_.counter_names.size());
  return *this;
}

HeartbeatBuilder& HeartbeatBuilder::add(const std::string& name, uint64_t value) {
  constexpr uint64_t kMax = static_cast<uint64_t>(std::numeric_limits<int64_t>::max());
  return add(name, static_cast<int64_t>(value > kMax ? kMax : value));
}

HeartbeatBuilder& HeartbeatBuilder::addMicroseconds(const std::string& name, double ms) {
  return add(name, static_cast<int64_t>(std::llround(std::isfinite(ms) ? ms * 1000.0 : 0.0)));
}

heartbeat_t HeartbeatBuilder::build() const {
  heartbeat_t hb = msg_;
  const ProcessUsage usage = ProcessUsage::current();
  hb.counter_names.push_back("cpu_ms");
  hb.counter_values.push_back(usage.cpu_ms);
  hb.counter_names.push_back("rss_kib");
  hb.counter_values.push_back(usage.rss_kib);
  hb.num_counters = static_cast<int32_t>(hb.counter_names.size());
  hb.utime = wallUtime();
  hb.pid = static_cast<int32_t>(::getpid());
  return hb;
}

}  // namespace cblox
