#include "core/mapping/planning_export.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <optional>

#include <opencv2/imgproc.hpp>

#include "core/common/text_format.h"
#include "core/eval/colormap.h"
#include "core/eval/trajectory_plot.h"
#include "core/geometry/image.h"
#include "core/io/atomic_file.h"
#include "core/mapping/output_path.h"

namespace cblox {

namespace {

using Clock = std::chrono::steady_clock;

Color distanceColor(VoxelState state, float distance, float max_distance) {
  if (state == VoxelState::kOccupied) return Color{0, 0, 0};
  if (state == VoxelState::kUnknown) return Color{128, 128, 128};
  return colormap(static_cast<double>(distance) / static_cast<double>(max_distance));
}

struct CellCounts {
  size_t free = 0, occupied = 0, unknown = 0;
};

CellCounts countCells(const LocalGrid& grid) {
  CellCounts c;
  for (const VoxelState s : grid.state) {
    if (s == VoxelState::kFree) {
      ++c.free;
    } else if (s == VoxelState::kOccupied) {
      ++c.occupied;
    } else {
      ++c.unknown;
    }
  }
  return c;
}

template <typename T>
void append(std::string* out, T value) {
  char bytes[sizeof(T)];
  std::memcpy(bytes, &value, sizeof(T));  // little-endian hosts only (x86-64, AArch64)
  out->append(bytes, sizeof(T));
}

// The file to write (writableOutputPath), or nullopt with reply->message saying why not.
std::optional<std::filesystem::path> outputFile(const std::filesystem::path& output_dir,
                                                const std::string& path, MapperReply* reply) {
  std::string error;
  std::optional<std::filesystem::path> target = writableOutputPath(output_dir, path, &error);
  if (!target) reply->message = error;
  return target;
}

}  // namespace

MapperReply exportDistanceGrid(const PlanningMap& planning, const Eigen::Vector3d& min_G,
                               const Eigen::Vector3d& max_G, double resolution,
                               const std::filesystem::path& output_dir, const std::string& path) {
  MapperReply reply;
  const std::optional<std::filesystem::path> target = outputFile(output_dir, path, &reply);
  if (!target) return reply;
  std::string error;
  const Clock::time_point start = Clock::now();
  LocalGrid grid;
  if (!planning.localGrid(min_G, max_G, resolution, &grid, &error)) {
    reply.message = "no grid: " + error;
    return reply;
  }
  const CellCounts counts = countCells(grid);
  const size_t observed = counts.free + counts.occupied;
  std::string ply =
      "ply\nformat binary_little_endian 1.0\n"
      "comment cblox distance grid: observed cells only (absent = unknown); state 1 free, 2 "
      "occupied; distance in metres, negative inside obstacles\n"
      "comment resolution " + fixed(resolution, 6) + " max_distance_m " +
      fixed(planning.config().max_distance_m, 3) + "\n"
      "element vertex " + std::to_string(observed) + "\n"
      "property float x\nproperty float y\nproperty float z\n"
      "property uchar red\nproperty uchar green\nproperty uchar blue\n"
      "property float distance\nproperty uchar state\nend_header\n";
  ply.reserve(ply.size() + observed * 20);
  const float max_distance = planning.config().max_distance_m;
  for (int k = 0; k < grid.size.z(); ++k) {
    for (int j = 0; j < grid.size.y(); ++j) {
      for (int i = 0; i < grid.size.x(); ++i) {
        const size_t c = grid.index(i, j, k);
        if (grid.state[c] == VoxelState::kUnknown) continue;
        const Eigen::Vector3f p = grid.cellCenter(i, j, k).cast<float>();
        append(&ply, p.x());
        append(&ply, p.y());
        append(&ply, p.z());
        const Color color = distanceColor(grid.state[c], grid.distance[c], max_distance);
        append(&ply, color.r);
        append(&ply, color.g);
        append(&ply, color.b);
        append(&ply, grid.distance[c]);
        append(&ply, static_cast<uint8_t>(grid.state[c]));
      }
    }
  }
  if (!writeFileAtomically(target->string(), ply, &error)) {
    reply.message = error;
    return reply;
  }
  const size_t cells = grid.state.size();
  reply.ok = true;
  reply.message = "wrote " + target->string() + ": " + std::to_string(observed) +
                  " observed cells of " + std::to_string(cells) + " (" +
                  std::to_string(counts.occupied) + " occupied)";
  reply.values = {{"path", target->string()},
                  {"cells", std::to_string(cells)},
                  {"free", std::to_string(counts.free)},
                  {"occupied", std::to_string(counts.occupied)},
                  {"unknown", std::to_string(counts.unknown)},
                  {"seconds", fixed(secondsSince(start), 3)}};
  return reply;
}

MapperReply exportDistanceSlice(const PlanningMap& planning, double z_G, double resolution,
                                const std::vector<Eigen::Vector3d>& trajectory_G,
                                const std::filesystem::path& output_dir, const std::string& path) {
  MapperReply reply;
  const std::optional<std::filesystem::path> target = outputFile(output_dir, path, &reply);
  if (!target) return reply;
  std::string error;
  if (!std::isfinite(z_G) || !std::isfinite(resolution) || !(resolution > 0.0)) {
    reply.message = "the height must be finite and the resolution finite and > 0";
    return reply;
  }
  const Eigen::AlignedBox3d bounds = planning.boundsG();
  if (bounds.isEmpty()) {
    reply.message = "the planning map has no distance field yet (an empty map)";
    return reply;
  }
  const Clock::time_point start = Clock::now();
  constexpr int kMaxSide = 1600;
  constexpr int kMinPictureSide = 600;
  const Eigen::Vector2d extent = (bounds.max() - bounds.min()).head<2>();
  double r = resolution;
  while (extent.maxCoeff() / r > kMaxSide) r *= 2.0;
  // One layer of cells centred on z_G: half a cell short of a second one.
  const Eigen::Vector3d min_G(bounds.min().x(), bounds.min().y(), z_G - 0.5 * r);
  const Eigen::Vector3d max_G(bounds.max().x(), bounds.max().y(), z_G);
  LocalGrid grid;
  if (!planning.localGrid(min_G, max_G, r, &grid, &error)) {
    reply.message = "no slice: " + error;
    return reply;
  }
  const CellCounts counts = countCells(grid);
  const float max_distance = planning.config().max_distance_m;
  // Each cell s x s pixels, so that small maps are still a picture one can read.
  const int w = grid.size.x(), h = grid.size.y();
  const int s = std::max(1, std::min(8, kMinPictureSide / std::max(w, h)));
  constexpr int kTop = 52, kLeft = 10, kRight = 90, kBottom = 10;
  ColorImage image(kLeft + s * w + kRight, kTop + s * h + kBottom, Color{255, 255, 255});
  for (int j = 0; j < h; ++j) {
    for (int i = 0; i < w; ++i) {
      const size_t c = grid.index(i, j, 0);
      const Color color = distanceColor(grid.state[c], grid.distance[c], max_distance);
      for (int v = 0; v < s; ++v) {
        for (int u = 0; u < s; ++u) image(kLeft + s * i + u, kTop + s * (h - 1 - j) + v) = color;
      }
    }
  }
  cv::Mat view(image.height, image.width, CV_8UC3, image.data.data());  // RGB
  const auto pixel = [&](const Eigen::Vector3d& p) {
    return cv::Point2d(kLeft + s * (p.x() - grid.origin.x()) / r,
                       kTop + s * h - s * (p.y() - grid.origin.y()) / r);
  };
  if (!trajectory_G.empty()) {
    std::vector<cv::Point> line;
    line.reserve(trajectory_G.size());
    for (const Eigen::Vector3d& p : trajectory_G) {
      const cv::Point2d q = pixel(p);
      line.emplace_back(static_cast<int>(std::lround(q.x)), static_cast<int>(std::lround(q.y)));
    }
    cv::polylines(view, line, false, cv::Scalar(230, 30, 30), 2, cv::LINE_AA);
    cv::circle(view, line.front(), 5, cv::Scalar(255, 255, 255), cv::FILLED, cv::LINE_AA);
    cv::circle(view, line.front(), 5, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
  }
  const cv::Scalar black(0, 0, 0);
  cv::putText(view,
              "distance field at z = " + fixed(z_G, 2) + " m, " + fixed(r * 100.0, 1) + " cm cells",
              cv::Point(kLeft, 18), cv::FONT_HERSHEY_SIMPLEX, 0.45, black, 1, cv::LINE_AA);
  cv::putText(view, "black: obstacle, grey: unknown, red: camera path", cv::Point(kLeft, 36),
              cv::FONT_HERSHEY_SIMPLEX, 0.4, black, 1, cv::LINE_AA);
  drawColorBar(&image, kLeft + s * w + 12, kTop, 16, std::max(40, std::min(s * h, 300)), 0.0,
               max_distance, "m");
  if (!writeColorImagePng(target->string(), image, &error)) {
    reply.message = error;
    return reply;
  }
  reply.ok = true;
  reply.message = "wrote " + target->string() + ": " + std::to_string(w) + " x " +
                  std::to_string(h) + " cells at " + fixed(r, 3) + " m";
  reply.values = {{"path", target->string()},
                  {"width", std::to_string(w)},
                  {"height", std::to_string(h)},
                  {"resolution", fixed(r, 4)},
                  {"free", std::to_string(counts.free)},
                  {"occupied", std::to_string(counts.occupied)},
                  {"unknown", std::to_string(counts.unknown)},
                  {"seconds", fixed(secondsSince(start), 3)}};
  return reply;
}

}  // namespace cblox
