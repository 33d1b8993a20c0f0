// The mesh stream's bytes on the bus: listens to a running cblox-mapper's CBLOX_MESH_UPDATE and
// CBLOX_SUBVOLUMES (scripts/bench_mesh_stream.sh starts it on a recorded run), keeps a
// MeshMirror, and per update period (one subvolume list) compares the incremental bytes that
// came with it against the whole mesh resent each time (a full refresh of what the mirror
// holds, as mesh_update_t bytes).
//
//   cblox-bench-mesh-stream --lcm-url URL --idle-s 5
//
// Prints one summary line, and a JSON object with --json FILE. Ends when no update came for
// --idle-s seconds after the first one (or after --max-s). Exit status: 0 done, 1 nothing
// heard or the stream was incomplete (a gap), 2 usage.

#include <chrono>
#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

#include <cblox/mesh_update_t.hpp>
#include <cblox/subvolume_list_t.hpp>
#include <lcm/lcm-cpp.hpp>
#include <nlohmann/json.hpp>

#include "core/mapping/mesh_mirror.h"
#include "daemon/common/cli.h"
#include "daemon/common/mesh_stream_codec.h"

namespace cblox {
namespace {

using Clock = std::chrono::steady_clock;

struct Counter {
  MeshMirror mirror;
  uint64_t incremental_bytes = 0, period_bytes = 0, messages = 0, gaps = 0, refused = 0;
  std::vector<double> period_incremental, period_whole;  // bytes per period
  Clock::time_point first, last;
  bool heard = false;

  void onUpdate(const lcm::ReceiveBuffer* rbuf, const std::string&, const mesh_update_t* m) {
    MeshUpdate update;
    std::string error;
    if (!decodeMeshUpdate(*m, &update, &error)) {
      ++refused;
      return;
    }
    const MeshMirror::Result r = mirror.apply(update);
    gaps += r.gap ? 1 : 0;
    // The first refresh (everything at once) is not an increment of a running map.
    if (heard) {
      incremental_bytes += rbuf->data_size;
      period_bytes += rbuf->data_size;
    }
    ++messages;
    last = Clock::now();
    if (!heard) first = last;
    heard = true;
  }

  // A period ended: the whole mesh, as one refresh of everything held, in mesh_update_t bytes.
  void onList(const lcm::ReceiveBuffer*, const std::string&, const subvolume_list_t* m) {
    SubvolumeList list;
    std::string error;
    if (decodeSubvolumeList(*m, &list, &error)) mirror.applySubvolumes(list);
    if (!heard) return;
    MeshUpdate whole;
    whole.block_size = mirror.blockSize();
    for (const auto& [id, blocks] : mirror.blocks()) {
      for (const auto& [key, mesh] : blocks) {
        whole.blocks.push_back(MeshBlockUpdate{id, unpackGridIndex(key), mesh});
      }
    }
    period_whole.push_back(static_cast<double>(encodeMeshUpdate(whole, 0).getEncodedSize()));
    period_incremental.push_back(static_cast<double>(period_bytes));
    period_bytes = 0;
  }
};

double mean(const std::vector<double>& v) {
  double s = 0;
  for (const double x : v) s += x;
  return v.empty() ? 0.0 : s / static_cast<double>(v.size());
}

}  // namespace
}  // namespace cblox

int main(int argc, char** argv) {
  std::string url, json_path;
  double idle_s = 5.0, max_s = 600.0;
  CLI::App app{"cblox-bench-mesh-stream: bytes of the mesh stream, incremental against whole",
               "cblox-bench-mesh-stream"};
  app.add_option("--lcm-url", url, "LCM URL")->required();
  app.add_option("--idle-s", idle_s, "stop after this long without an update")->capture_default_str();
  app.add_option("--max-s", max_s, "stop after this long in any case")->capture_default_str();
  app.add_option("--json", json_path, "also write the figures here");
  if (const std::optional<int> code = cblox::parseCommandLine(app, argc, argv)) return *code;

  lcm::LCM lcm(url);
  if (!lcm.good()) return 1;
  cblox::Counter counter;
  lcm.subscribe("CBLOX_MESH_UPDATE", &cblox::Counter::onUpdate, &counter);
  lcm.subscribe("CBLOX_SUBVOLUMES", &cblox::Counter::onList, &counter);
  const auto start = cblox::Clock::now();
  while (cblox::Clock::now() - start < std::chrono::duration<double>(max_s)) {
    lcm.handleTimeout(100);
    if (counter.heard &&
        cblox::Clock::now() - counter.last > std::chrono::duration<double>(idle_s)) {
      break;
    }
  }
  if (!counter.heard) {
    std::fprintf(stderr, "cblox-bench-mesh-stream: no CBLOX_MESH_UPDATE heard\n");
    return 1;
  }
  // The run: from the first update to the last (the idle tail is not part of it).
  const double seconds = std::chrono::duration<double>(counter.last - counter.first).count();
  const double incremental_per_s = seconds > 0 ? counter.incremental_bytes / seconds : 0.0;
  const double whole_per_period = cblox::mean(counter.period_whole);
  const double final_whole = counter.period_whole.empty() ? 0.0 : counter.period_whole.back();
  double largest_period = 0;
  for (const double b : counter.period_incremental) largest_period = std::max(largest_period, b);
  std::printf(
      "mesh stream: %.1f s, %zu periods, %llu messages, %zu blocks held at the end; incremental "
      "%.1f KiB/s (largest period %.1f KiB); whole mesh each period %.1f KiB on average, %.1f "
      "KiB at the end; incremental / whole %.3f; gaps %llu, refused %llu, complete %s\n",
      seconds, counter.period_whole.size(), static_cast<unsigned long long>(counter.messages),
      counter.mirror.numBlocks(), incremental_per_s / 1024.0, largest_period / 1024.0,
      whole_per_period / 1024.0, final_whole / 1024.0,
      whole_per_period > 0 ? incremental_per_s / whole_per_period : 0.0,
      static_cast<unsigned long long>(counter.gaps), static_cast<unsigned long long>(counter.refused),
      counter.mirror.complete() ? "yes" : "no");
  if (!json_path.empty()) {
    nlohmann::json j;
    j["seconds"] = seconds;
    j["periods"] = counter.period_whole.size();
    j["messages"] = counter.messages;
    j["blocks_at_end"] = counter.mirror.numBlocks();
    j["incremental_bytes_per_s"] = incremental_per_s;
    j["largest_period_bytes"] = largest_period;
    j["whole_bytes_per_period_mean"] = whole_per_period;
    j["whole_bytes_at_end"] = final_whole;
    j["gaps"] = counter.gaps;
    j["complete"] = counter.mirror.complete();
    std::ofstream(json_path) << j.dump(2) << "\n";
  }
  return counter.gaps == 0 && counter.mirror.complete() ? 0 : 1;
}
