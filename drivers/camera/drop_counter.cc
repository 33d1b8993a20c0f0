#include "drivers/camera/drop_counter.h"

#include <cstdio>
#include <utility>

namespace cblox {

DropCounter::DropCounter(std::string prefix, Sink sink)
    : prefix_(std::move(prefix)), sink_(std::move(sink)) {}

void DropCounter::count(std::string_view kind, const std::string& message) {
  auto it = counts_.find(kind);
  if (it == counts_.end()) {
    counts_.emplace(std::string(kind), 1);
    if (sink_) {
      sink_(prefix_ + ": dropped a frame (" + std::string(kind) + "): " + message +
            " (further drops of this kind are only counted)");
    }
    return;
  }
  ++it->second;
}

int64_t DropCounter::count(std::string_view kind) const {
  const auto it = counts_.find(kind);
  return it == counts_.end() ? 0 : it->second;
}

int64_t DropCounter::total() const {
  int64_t sum = 0;
  for (const auto& [kind, n] : counts_) sum += n;
  return sum;
}

std::string DropCounter::summary() const {
  if (counts_.empty()) return "none";
  std::string text;
  for (const auto& [kind, n] : counts_) {
    if (!text.empty()) text += ' ';
    text += kind + "=" + std::to_string(n);
  }
  return text;
}

void DropCounter::writeToStderr(const std::string& line) {
  std::fprintf(stderr, "%s\n", line.c_str());
}

}  // namespace cblox
