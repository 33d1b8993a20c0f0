// What the message guard's wire check costs next to LCM's own decode (Google Benchmark):
// a 752x480 grey stereo pair (the tracker's input), a depth frame with colour (the mapper's),
// and a keyframe with 1000 landmark ids. The check walks lengths and skips byte arrays, so it
// should cost next to nothing beside the decode that copies the pixels.

#include <cstdint>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>
#include <cblox/depth_frame_t.hpp>
#include <cblox/keyframe_t.hpp>
#include <cblox/stereo_pair_t.hpp>

#include "lcmtypes/wire_check.h"

namespace {

using Bytes = std::vector<uint8_t>;

cblox::image_t image(int width, int height, int bytes_per_pixel, int8_t format) {
  cblox::image_t m{};
  m.camera_id = "cam0";
  m.width = width;
  m.height = height;
  m.row_stride = width * bytes_per_pixel;
  m.pixel_format = format;
  m.size = m.row_stride * height;
  m.data.assign(static_cast<size_t>(m.size), 0x5A);
  return m;
}

template <typename Msg>
Bytes encode(const Msg& msg) {
  Bytes bytes(static_cast<size_t>(msg.getEncodedSize()));
  msg.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  return bytes;
}

Bytes stereoPair() {
  cblox::stereo_pair_t m{};
  m.left = image(752, 480, 1, cblox::image_t::GRAY8);
  m.right = image(752, 480, 1, cblox::image_t::GRAY8);
  return encode(m);
}

Bytes depthFrame() {
  cblox::depth_frame_t m{};
  m.depth = image(752, 480, 2, cblox::image_t::DEPTH_U16);
  m.has_color = true;
  m.color = image(752, 480, 3, cblox::image_t::RGB8);
  return encode(m);
}

Bytes keyframe() {
  cblox::keyframe_t m{};
  m.num_landmarks = 1000;
  m.landmark_ids.assign(1000, 42);
  return encode(m);
}

template <typename Msg>
void BM_CheckWire(benchmark::State& state, Bytes (*make)()) {
  const Bytes bytes = make();
  for (auto _ : state) {
    const cblox::WireCheck check = cblox::checkWire(bytes.data(), bytes.size(), Msg::getTypeName(),
                                                    Msg::getHash());
    benchmark::DoNotOptimize(check.error);
  }
  state.SetBytesProcessed(static_cast<int64_t>(state.iterations() * bytes.size()));
}

template <typename Msg>
void BM_LcmDecode(benchmark::State& state, Bytes (*make)()) {
  const Bytes bytes = make();
  for (auto _ : state) {
    Msg msg;
    benchmark::DoNotOptimize(msg.decode(bytes.data(), 0, static_cast<int>(bytes.size())));
  }
  state.SetBytesProcessed(static_cast<int64_t>(state.iterations() * bytes.size()));
}

template <typename Msg>
void BM_DecodeChecked(benchmark::State& state, Bytes (*make)()) {
  const Bytes bytes = make();
  for (auto _ : state) {
    Msg msg;
    benchmark::DoNotOptimize(cblox::decodeChecked(bytes.data(), bytes.size(), &msg).error);
  }
  state.SetBytesProcessed(static_cast<int64_t>(state.iterations() * bytes.size()));
}

template <typename Msg>
void registerAll(const char* name, Bytes (*make)()) {
  benchmark::RegisterBenchmark((std::string("CheckWire/") + name).c_str(),
                               [make](benchmark::State& st) { BM_CheckWire<Msg>(st, make); });
  benchmark::RegisterBenchmark((std::string("LcmDecode/") + name).c_str(),
                               [make](benchmark::State& st) { BM_LcmDecode<Msg>(st, make); });
  benchmark::RegisterBenchmark((std::string("DecodeChecked/") + name).c_str(),
                               [make](benchmark::State& st) { BM_DecodeChecked<Msg>(st, make); });
}

}  // namespace

int main(int argc, char** argv) {
  registerAll<cblox::stereo_pair_t>("stereo_752x480", stereoPair);
  registerAll<cblox::depth_frame_t>("depth_rgb_752x480", depthFrame);
  registerAll<cblox::keyframe_t>("keyframe_1000_landmarks", keyframe);
  benchmark::Initialize(&argc, argv);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
