#include "core/eval/mesh_accuracy.h"

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <random>
#include <thread>
#include <unordered_map>
#include <unordered_set>

#include <nlohmann/json.hpp>

#include "core/tsdf/block_index.h"
#include "core/tsdf/voxel.h"

namespace cblox {
namespace {

void setError(std::string* error, std::string message) {
  if (error != nullptr) *error = std::move(message);
}

// Runs body(begin, end) over [0, n) split into contiguous ranges, one per thread (the calling
// thread takes the first range). Small inputs run on the calling thread only.
template <typename Body>
void parallelFor(size_t n, int num_threads, const Body& body) {
  constexpr size_t kMinPerThread = 256;
  const size_t threads =
      std::clamp<size_t>(n / kMinPerThread, 1, static_cast<size_t>(std::max(1, num_threads)));
  if (threads == 1) {
    body(size_t{0}, n);
    return;
  }
  std::vector<std::thread> workers;
  workers.reserve(threads - 1);
  const size_t chunk = (n + threads - 1) / threads;
  for (size_t t = 1; t < threads; ++t) {
    const size_t begin = std::min(n, t * chunk);
    const size_t end = std::min(n, begin + chunk);
    workers.emplace_back([&body, begin, end] { body(begin, end); });
  }
  body(size_t{0}, std::min(n, chunk));
  for (std::thread& worker : workers) worker.join();
}

// Uniform double in [0, 1) from the top 53 bits (the same on every standard library, unlike
// std::uniform_real_distribution).
double uniform01(std::mt19937_64& rng) { return static_cast<double>(rng() >> 11) * 0x1.0p-53; }

Eigen::Vector3d vertex(const Mesh& mesh, int index) {
  return mesh.vertices[static_cast<size_t>(index)].cast<double>();
}

double triangleArea(const Mesh& mesh, const Eigen::Vector3i& t) {
  const Eigen::Vector3d a = vertex(mesh, t[0]);
  return 0.5 * (vertex(mesh, t[1]) - a).cross(vertex(mesh, t[2]) - a).norm();
}

// Stratified area-uniform samples of the mesh surface (see MeshAccuracy); `cumulative` holds
// the running sum of the triangle areas.
std::vector<Eigen::Vector3d> sampleSurface(const Mesh& mesh, const std::vector<double>& cumulative,
                                           size_t count, uint64_t seed) {
  std::vector<Eigen::Vector3d> samples;
  samples.reserve(count);
  std::mt19937_64 rng(seed);
  const double total = cumulative.back();
  for (size_t i = 0; i < count; ++i) {
    const double position = (static_cast<double>(i) + uniform01(rng)) / static_cast<double>(count);
    const size_t t =
        std::min<size_t>(static_cast<size_t>(std::upper_bound(cumulative.begin(), cumulative.end(),
                                                              position * total) -
                                             cumulative.begin()),
                         cumulative.size() - 1);
    double a = uniform01(rng);
    double b = uniform01(rng);
    if (a + b > 1.0) {
      a = 1.0 - a;
      b = 1.0 - b;
    }
    const Eigen::Vector3i& tri = mesh.triangles[t];
    const Eigen::Vector3d v0 = vertex(mesh, tri[0]);
    samples.push_back(v0 + a * (vertex(mesh, tri[1]) - v0) + b * (vertex(mesh, tri[2]) - v0));
  }
  return samples;
}

// Nearest-vertex queries within a fixed radius on a hashed grid of cell size `radius`.
class VertexGrid {
 public:
  VertexGrid(const std::vector<Eigen::Vector3f>& vertices, double radius)
      : vertices_(vertices), inverse_cell_(1.0 / radius), radius_(radius) {
    for (size_t i = 0; i < vertices.size(); ++i) {
      cells_[key(cell(vertices[i].cast<double>()))].push_back(static_cast<uint32_t>(i));
    }
  }

  // True when a vertex lies within the radius (inclusive) of p.
  bool anyWithin(const Eigen::Vector3d& p) const {
    const std::array<int64_t, 3> c = cell(p);
    const double radius_squared = radius_ * radius_;
    for (int64_t dz = -1; dz <= 1; ++dz) {
      for (int64_t dy = -1; dy <= 1; ++dy) {
        for (int64_t dx = -1; dx <= 1; ++dx) {
          const auto it = cells_.find(key({c[0] + dx, c[1] + dy, c[2] + dz}));
          if (it == cells_.end()) continue;
          for (const uint32_t i : it->second) {
            if ((vertices_[i].cast<double>() - p).squaredNorm() <= radius_squared) return true;
          }
        }
      }
    }
    return false;
  }

 private:
  std::array<int64_t, 3> cell(const Eigen::Vector3d& p) const {
    // Clamped so that far-away points cannot overflow; the clamp only merges cells that lie
    // beyond 2^40 cells, where no vertex within the radius can be missed.
    constexpr double kLimit = 1099511627776.0;  // 2^40
    std::array<int64_t, 3> c;
    for (int k = 0; k < 3; ++k) {
      c[static_cast<size_t>(k)] =
          static_cast<int64_t>(std::floor(std::clamp(p[k] * inverse_cell_, -kLimit, kLimit)));
    }
    return c;
  }
  static uint64_t key(const std::array<int64_t, 3>& c) {
    // 21 bits per axis would alias on large grids; a 64-bit mix keeps the map correct (every
    // candidate is distance-checked) and only costs extra checks on a collision.
    uint64_t h = 0x9e3779b97f4a7c15ull;
    for (const int64_t v : c) {
      h ^= static_cast<uint64_t>(v) + 0x9e3779b97f4a7c15ull + (h << 6) + (h >> 2);
    }
    return h;
  }

  const std::vector<Eigen::Vector3f>& vertices_;
  double inverse_cell_;
  double radius_;
  std::unordered_map<uint64_t, std::vector<uint32_t>> cells_;
};

nlohmann::ordered_json alignmentJson(const std::optional<Alignment>& alignment) {
  const Alignment a = alignment.value_or(Alignment{});
  const Eigen::Quaterniond& q = a.T_A_B.rotation();
  const Eigen::Vector3d& t = a.T_A_B.translation();
  return {{"applied", alignment.has_value()},
          {"scale", a.scale},
          {"rotation_xyzw", {q.x(), q.y(), q.z(), q.w()}},
          {"translation_m", {t.x(), t.y(), t.z()}}};
}

}  // namespace

std::string MeshAccuracyConfig::validate() const {
  if (!(completeness_threshold_m > 0.0) || !std::isfinite(completeness_threshold_m)) {
    return "mesh accuracy: completeness_threshold_m must be finite and > 0, got " +
           std::to_string(completeness_threshold_m);
  }
  if (!(surface_sample_spacing_m > 0.0) || !std::isfinite(surface_sample_spacing_m)) {
    return "mesh accuracy: surface_sample_spacing_m must be finite and > 0, got " +
           std::to_string(surface_sample_spacing_m);
  }
  if (max_surface_samples < 1) return "mesh accuracy: max_surface_samples must be >= 1, got 0";
  if (T_G_R.has_value()) {
    if (!(T_G_R->scale > 0.0) || !std::isfinite(T_G_R->scale)) {
      return "mesh accuracy: T_G_R.scale must be finite and > 0, got " +
             std::to_string(T_G_R->scale);
    }
    if (!T_G_R->T_A_B.translation().allFinite() || !T_G_R->T_A_B.rotation().coeffs().allFinite()) {
      return "mesh accuracy: T_G_R is not finite";
    }
  }
  if (!(max_distance_m > 0.0)) {
    return "mesh accuracy: max_distance_m must be > 0 (infinity for no limit), got " +
           std::to_string(max_distance_m);
  }
  if (num_threads < 1 || num_threads > 64) {
    return "mesh accuracy: num_threads must be in [1, 64], got " + std::to_string(num_threads);
  }
  return "";
}

Mesh alignMesh(const Mesh& mesh, const Alignment& alignment) {
  Mesh aligned = mesh;
  for (Eigen::Vector3f& v : aligned.vertices) v = alignment.apply(v.cast<double>()).cast<float>();
  const Eigen::Matrix3f R = alignment.T_A_B.rotationMatrix().cast<float>();
  for (Eigen::Vector3f& n : aligned.normals) n = R * n;
  return aligned;
}

std::optional<MeshAccuracy> evaluateMeshAccuracy(const TriangleMeshRaycaster& ground_truth,
                                                 const Mesh& reconstruction,
                                                 const MeshAccuracyConfig& options,
                                                 std::string* error) {
  if (std::string message = options.validate(); !message.empty()) {
    setError(error, std::move(message));
    return std::nullopt;
  }
  if (reconstruction.vertices.empty()) {
    setError(error, "mesh accuracy: the reconstruction has no vertex");
    return std::nullopt;
  }
  if (std::string message = reconstruction.validate(); !message.empty()) {
    setError(error, "mesh accuracy: the reconstruction is malformed: " + message);
    return std::nullopt;
  }
  const Mesh aligned =
      options.T_G_R.has_value() ? alignMesh(reconstruction, *options.T_G_R) : reconstruction;
  for (size_t i = 0; i < aligned.vertices.size(); ++i) {
    if (!aligned.vertices[i].allFinite()) {
      setError(error, "mesh accuracy: reconstruction vertex " + std::to_string(i) +
                          " is not finite" + (options.T_G_R ? " after the alignment" : ""));
      return std::nullopt;
    }
  }

  const Mesh& truth = ground_truth.mesh();
  std::vector<double> cumulative;
  cumulative.reserve(truth.triangles.size());
  double area = 0.0;
  for (const Eigen::Vector3i& t : truth.triangles) {
    area += triangleArea(truth, t);
    cumulative.push_back(area);
  }
  if (!(area > 0.0) || !std::isfinite(area)) {
    setError(error, "mesh accuracy: the ground truth has no surface area (" +
                        std::to_string(truth.triangles.size()) + " triangles, area " +
                        std::to_string(area) + " m^2)");
    return std::nullopt;
  }

  MeshAccuracy result;
  result.reconstruction_vertices = aligned.vertices.size();
  result.reconstruction_triangles = aligned.triangles.size();
  result.ground_truth_triangles = truth.triangles.size();
  result.ground_truth_area_m2 = area;
  result.T_G_R = options.T_G_R;
  result.max_distance_m = options.max_distance_m;
  result.completeness_threshold_m = options.completeness_threshold_m;

  // Accuracy: reconstruction vertex -> ground-truth surface.
  result.vertex_errors_m.assign(aligned.vertices.size(), 0.0);
  parallelFor(aligned.vertices.size(), options.num_threads, [&](size_t begin, size_t end) {
    for (size_t i = begin; i < end; ++i) {
      result.vertex_errors_m[i] =
          ground_truth.closestPoint(aligned.vertices[i].cast<double>(), options.max_distance_m)
              .distance;  // infinity when nothing is within max_distance_m
    }
  });
  std::vector<double> inliers;
  inliers.reserve(result.vertex_errors_m.size());
  size_t accurate = 0;
  for (const double e : result.vertex_errors_m) {
    if (std::isfinite(e)) inliers.push_back(e);
    if (e <= options.completeness_threshold_m) ++accurate;
  }
  result.outlier_vertices = result.vertex_errors_m.size() - inliers.size();
  result.accuracy_m = computeErrorStatistics(std::move(inliers));
  result.precision =
      static_cast<double>(accurate) / static_cast<double>(result.vertex_errors_m.size());

  // Completeness: ground-truth samples -> reconstruction.
  const double wanted =
      std::ceil(area / (options.surface_sample_spacing_m * options.surface_sample_spacing_m));
  const size_t count = std::isfinite(wanted)
                           ? std::clamp<size_t>(static_cast<size_t>(std::min(wanted, 1e18)), 1,
                                                options.max_surface_samples)
                           : options.max_surface_samples;
  const std::vector<Eigen::Vector3d> samples =
      sampleSurface(truth, cumulative, count, options.seed);
  result.ground_truth_samples = samples.size();
  result.sample_spacing_m = std::sqrt(area / static_cast<double>(samples.size()));
  std::vector<uint8_t> covered(samples.size(), 0);
  const double threshold = options.completeness_threshold_m;
  if (!aligned.triangles.empty()) {
    std::string raycaster_error;
    const std::unique_ptr<TriangleMeshRaycaster> reconstructed =
        TriangleMeshRaycaster::create(aligned, &raycaster_error);
    if (!reconstructed) {
      setError(error, "mesh accuracy: reconstruction: " + raycaster_error);
      return std::nullopt;
    }
    parallelFor(samples.size(), options.num_threads, [&](size_t begin, size_t end) {
      for (size_t i = begin; i < end; ++i) {
        covered[i] = reconstructed->closestPoint(samples[i], threshold).found() ? 1 : 0;
      }
    });
  } else {
    result.completeness_reference = "vertices";
    const VertexGrid grid(aligned.vertices, threshold);
    parallelFor(samples.size(), options.num_threads, [&](size_t begin, size_t end) {
      for (size_t i = begin; i < end; ++i) covered[i] = grid.anyWithin(samples[i]) ? 1 : 0;
    });
  }
  const size_t covered_count = static_cast<size_t>(std::count(covered.begin(), covered.end(), 1));
  result.completeness = static_cast<double>(covered_count) / static_cast<double>(samples.size());
  const double sum = result.precision + result.completeness;
  result.f_score = sum > 0.0 ? 2.0 * result.precision * result.completeness / sum : 0.0;
  return result;
}

nlohmann::ordered_json MeshAccuracy::toJson() const {
  nlohmann::ordered_json root;
  root["reconstruction_vertices"] = reconstruction_vertices;
  root["reconstruction_triangles"] = reconstruction_triangles;
  root["ground_truth_triangles"] = ground_truth_triangles;
  root["ground_truth_area_m2"] = ground_truth_area_m2;
  root["alignment"] = alignmentJson(T_G_R);
  root["max_distance_m"] = max_distance_m;
  root["accuracy"] = {{"vertices", accuracy_m.count},  {"outlier_vertices", outlier_vertices},
                      {"rmse_m", accuracy_m.rmse},     {"mean_m", accuracy_m.mean},
                      {"median_m", accuracy_m.median}, {"p90_m", accuracy_m.p90},
                      {"std_m", accuracy_m.stddev},    {"min_m", accuracy_m.min},
                      {"max_m", accuracy_m.max}};
  root["completeness"] = {{"threshold_m", completeness_threshold_m},
                          {"ground_truth_samples", ground_truth_samples},
                          {"sample_spacing_m", sample_spacing_m},
                          {"reference", completeness_reference},
                          {"completeness", completeness},
                          {"precision", precision},
                          {"f_score", f_score}};
  return root;
}

std::optional<SurfaceBlockCount> countSurfaceBlocks(const Mesh& mesh, const LayerConfig& grid,
                                                    std::string* error) {
  if (std::string message = grid.validate(); !message.empty()) {
    setError(error, "surface blocks: " + message);
    return std::nullopt;
  }
  // The block index exactly as TsdfLayer::blockIndexFromPoint() computes it (float).
  const float block_size_inv = 1.0f / (grid.voxel_size * static_cast<float>(grid.voxels_per_side));
  std::unordered_set<uint64_t> blocks;
  for (size_t i = 0; i < mesh.vertices.size(); ++i) {
    const Eigen::Vector3f& v = mesh.vertices[i];
    if (!v.allFinite()) {
      setError(error, "surface blocks: vertex " + std::to_string(i) + " is not finite");
      return std::nullopt;
    }
    const Eigen::Vector3f scaled = v * block_size_inv;
    if (scaled.cwiseAbs().maxCoeff() >= static_cast<float>(kGridIndexMax)) {
      setError(error, "surface blocks: vertex " + std::to_string(i) +
                          " lies outside the packable block range of TsdfLayer");
      return std::nullopt;
    }
    blocks.insert(packGridIndex(gridIndexFromPoint(v, block_size_inv)));
  }
  SurfaceBlockCount count;
  // The float voxel size as the double with the same shortest text (0.02f -> 0.02, not
  // 0.0199999996), so that reports show the configured value.
  char text[32];
  const auto written = std::to_chars(text, text + sizeof(text), grid.voxel_size);
  std::from_chars(text, written.ptr, count.voxel_size_m);
  count.voxels_per_side = grid.voxels_per_side;
  count.blocks = blocks.size();
  const size_t voxels =
      static_cast<size_t>(grid.voxels_per_side) * grid.voxels_per_side * grid.voxels_per_side;
  count.voxel_bytes = count.blocks * voxels * sizeof(TsdfVoxel);
  return count;
}

}  // namespace cblox
