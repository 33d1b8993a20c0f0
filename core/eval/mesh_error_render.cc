#include "core/eval/mesh_error_render.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <memory>
#include <numbers>
#include <thread>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "core/eval/colormap.h"
#include "core/eval/trajectory_plot.h"
#include "core/raycast/triangle_mesh_raycaster.h"

namespace cblox {
namespace {

void setError(std::string* error, std::string message) {
  if (error != nullptr) *error = std::move(message);
}

constexpr double kAzimuthDeg = -60.0;
constexpr double kElevationDeg = 35.0;
constexpr double kFill = 0.92;      // share of the picture the automatic view may use
constexpr int kBarAreaWidth = 110;  // right of the mesh: colour bar and its labels
constexpr int kTitleHeight = 40;
constexpr int kMaxBackFaceSkips = 64;

double radians(double degrees) { return degrees * std::numbers::pi / 180.0; }

// Camera axes for a view direction, world z up (y when looking along z).
struct CameraBasis {
  Eigen::Vector3d forward;
  Eigen::Vector3d right;
  Eigen::Vector3d up;
};

CameraBasis cameraBasis(const Eigen::Vector3d& forward_direction) {
  CameraBasis basis;
  basis.forward = forward_direction.normalized();
  const Eigen::Vector3d world_up =
      std::abs(basis.forward.z()) > 0.999 ? Eigen::Vector3d::UnitY() : Eigen::Vector3d::UnitZ();
  basis.right = basis.forward.cross(world_up).normalized();
  basis.up = basis.right.cross(basis.forward);
  return basis;
}

// Where the mesh is drawn: a pinhole camera centred on the area left of the colour bar.
struct View {
  cv::Rect area;
  double focal_px = 1.0;
  Eigen::Vector3d eye;
  CameraBasis basis;
};

Color shade(const Color& c, double factor) {
  const auto channel = [factor](uint8_t value) {
    return static_cast<uint8_t>(std::clamp(std::lround(value * factor), 0L, 255L));
  };
  return Color{channel(c.r), channel(c.g), channel(c.b)};
}

// Renders pixel rows [row_begin, row_end) of the area into `image`.
void renderRows(const TriangleMeshRaycaster& raycaster, const std::vector<double>& errors,
                const MeshErrorRenderConfig& options, const View& view, int row_begin, int row_end,
                ColorImage* image) {
  const int ss = options.supersampling;
  const int columns = view.area.width * ss;
  std::vector<Ray> rays(static_cast<size_t>(columns));
  std::vector<RaycastHit> hits(rays.size());
  std::vector<std::array<double, 3>> sums(static_cast<size_t>(view.area.width));
  const Eigen::Vector3f eye = view.eye.cast<float>();
  const double cx = 0.5 * view.area.width;
  const double cy = 0.5 * view.area.height;
  const Mesh& mesh = raycaster.mesh();
  for (int row = row_begin; row < row_end; ++row) {
    std::fill(sums.begin(), sums.end(), std::array<double, 3>{0.0, 0.0, 0.0});
    for (int sub_row = 0; sub_row < ss; ++sub_row) {
      const double y = (row + (sub_row + 0.5) / ss - cy) / view.focal_px;
      for (int column = 0; column < columns; ++column) {
        const double x = (static_cast<double>(column) + 0.5) / ss;
        const Eigen::Vector3d direction =
            view.basis.forward + (x - cx) / view.focal_px * view.basis.right - y * view.basis.up;
        Ray& ray = rays[static_cast<size_t>(column)];
        ray.origin = eye;
        ray.direction = direction.cast<float>();
        ray.t_near = 0.0f;
        ray.t_far = std::numeric_limits<float>::infinity();
      }
      raycaster.intersect(rays, hits);
      for (int column = 0; column < columns; ++column) {
        Ray ray = rays[static_cast<size_t>(column)];
        RaycastHit hit = hits[static_cast<size_t>(column)];
        if (options.cull_back_faces) {
          // See through back faces: continue the ray just past each one.
          for (int skip = 0;
               skip < kMaxBackFaceSkips && hit.hit() && hit.normal.dot(ray.direction) > 0.0f;
               ++skip) {
            ray.t_near = hit.t * (1.0f + 1e-6f) + 1e-6f;
            raycaster.intersect(ray, &hit);
          }
          if (hit.hit() && hit.normal.dot(ray.direction) > 0.0f) hit = RaycastHit();
        }
        Color color = options.background;
        if (hit.hit()) {
          const Eigen::Vector3i& t = mesh.triangles[hit.triangle];
          const double e = (1.0 - hit.u - hit.v) * errors[static_cast<size_t>(t[0])] +
                           hit.u * errors[static_cast<size_t>(t[1])] +
                           hit.v * errors[static_cast<size_t>(t[2])];
          const double cosine =
              std::abs(hit.normal.dot(ray.direction)) / std::max(1e-12f, ray.direction.norm());
          color = shade(colormap(e / options.max_error_m), 0.6 + 0.4 * cosine);
        }
        std::array<double, 3>& sum = sums[static_cast<size_t>(column / ss)];
        sum[0] += color.r;
        sum[1] += color.g;
        sum[2] += color.b;
      }
    }
    const double n = static_cast<double>(ss * ss);
    for (int u = 0; u < view.area.width; ++u) {
      const std::array<double, 3>& sum = sums[static_cast<size_t>(u)];
      (*image)(view.area.x + u, view.area.y + row) =
          Color{static_cast<uint8_t>(std::lround(sum[0] / n)),
                static_cast<uint8_t>(std::lround(sum[1] / n)),
                static_cast<uint8_t>(std::lround(sum[2] / n))};
    }
  }
}

}  // namespace

std::string MeshErrorRenderConfig::validate() const {
  if (width < 200 || width > 10000) {
    return "mesh error render: width must be in [200, 10000] pixels, got " + std::to_string(width);
  }
  if (height < 150 || height > 10000) {
    return "mesh error render: height must be in [150, 10000] pixels, got " +
           std::to_string(height);
  }
  if (!(vertical_fov_deg >= 10.0 && vertical_fov_deg <= 120.0)) {
    return "mesh error render: vertical_fov_deg must be in [10, 120], got " +
           std::to_string(vertical_fov_deg);
  }
  if (viewpoint.has_value() && (!viewpoint->eye.allFinite() || !viewpoint->look_at.allFinite())) {
    return "mesh error render: the viewpoint is not finite";
  }
  if (viewpoint.has_value() && (viewpoint->eye - viewpoint->look_at).norm() <= 0.0) {
    return "mesh error render: the viewpoint's eye and look_at points coincide";
  }
  if (!(max_error_m > 0.0) || !std::isfinite(max_error_m)) {
    return "mesh error render: max_error_m must be finite and > 0, got " +
           std::to_string(max_error_m);
  }
  if (supersampling < 1 || supersampling > 4) {
    return "mesh error render: supersampling must be in [1, 4], got " +
           std::to_string(supersampling);
  }
  if (num_threads < 1 || num_threads > 64) {
    return "mesh error render: num_threads must be in [1, 64], got " + std::to_string(num_threads);
  }
  return "";
}

MeshViewpoint automaticViewpoint(const Eigen::AlignedBox3d& bounds, double vertical_fov_deg,
                                 double aspect) {
  const double azimuth = radians(kAzimuthDeg);
  const double elevation = radians(kElevationDeg);
  const Eigen::Vector3d to_eye(std::cos(elevation) * std::cos(azimuth),
                               std::cos(elevation) * std::sin(azimuth), std::sin(elevation));
  MeshViewpoint view;
  if (bounds.isEmpty() || !bounds.min().allFinite() || !bounds.max().allFinite()) {
    view.look_at = Eigen::Vector3d::Zero();
    view.eye = to_eye;
    return view;
  }
  view.look_at = bounds.center();
  const CameraBasis basis = cameraBasis(-to_eye);
  const double tan_y = kFill * std::tan(0.5 * radians(vertical_fov_deg));
  const double tan_x = tan_y * (aspect > 0.0 && std::isfinite(aspect) ? aspect : 1.0);
  const double diagonal = bounds.diagonal().norm();
  if (!(diagonal > 1e-9)) {  // a single point
    view.eye = view.look_at + to_eye;
    return view;
  }
  double distance = 0.0;
  for (int corner = 0; corner < 8; ++corner) {
    const Eigen::Vector3d relative =
        bounds.corner(static_cast<Eigen::AlignedBox3d::CornerType>(corner)) - view.look_at;
    const double depth_offset = relative.dot(basis.forward);
    distance = std::max({distance, std::abs(relative.dot(basis.right)) / tan_x - depth_offset,
                         std::abs(relative.dot(basis.up)) / tan_y - depth_offset,
                         1e-3 * diagonal - depth_offset});  // every corner in front
  }
  view.eye = view.look_at + distance * to_eye;
  return view;
}

std::optional<ColorImage> renderMeshError(const Mesh& mesh, std::span<const double> vertex_errors_m,
                                          const MeshErrorRenderConfig& options,
                                          std::string* error) {
  if (std::string message = options.validate(); !message.empty()) {
    setError(error, std::move(message));
    return std::nullopt;
  }
  if (vertex_errors_m.size() != mesh.vertices.size()) {
    setError(error, "mesh error render: " + std::to_string(vertex_errors_m.size()) +
                        " vertex errors for " + std::to_string(mesh.vertices.size()) + " vertices");
    return std::nullopt;
  }
  std::vector<double> errors(vertex_errors_m.begin(), vertex_errors_m.end());
  for (size_t i = 0; i < errors.size(); ++i) {
    if (!(errors[i] >= 0.0)) {
      setError(error, "mesh error render: the error of vertex " + std::to_string(i) +
                          " is negative or NaN");
      return std::nullopt;
    }
    errors[i] = std::min(errors[i], options.max_error_m);
  }
  std::string raycaster_error;
  const std::unique_ptr<TriangleMeshRaycaster> raycaster =
      TriangleMeshRaycaster::create(mesh, &raycaster_error);
  if (!raycaster) {
    setError(error, "mesh error render: " + raycaster_error);
    return std::nullopt;
  }

  View view;
  const int top = options.title.empty() ? 0 : kTitleHeight;
  view.area = cv::Rect(0, top, options.width - kBarAreaWidth, options.height - top);
  const double aspect = static_cast<double>(view.area.width) / view.area.height;
  const MeshViewpoint viewpoint = options.viewpoint.value_or(
      automaticViewpoint(raycaster->bounds().cast<double>(), options.vertical_fov_deg, aspect));
  view.eye = viewpoint.eye;
  view.basis = cameraBasis(viewpoint.look_at - viewpoint.eye);
  view.focal_px = 0.5 * view.area.height / std::tan(0.5 * radians(options.vertical_fov_deg));

  ColorImage image(options.width, options.height, options.background);
  const int threads = std::clamp(options.num_threads, 1, view.area.height);
  std::vector<std::thread> workers;
  const int chunk = (view.area.height + threads - 1) / threads;
  for (int t = 1; t < threads; ++t) {
    const int begin = std::min(view.area.height, t * chunk);
    const int end = std::min(view.area.height, begin + chunk);
    workers.emplace_back(
        [&, begin, end] { renderRows(*raycaster, errors, options, view, begin, end, &image); });
  }
  renderRows(*raycaster, errors, options, view, 0, std::min(view.area.height, chunk), &image);
  for (std::thread& worker : workers) worker.join();

  // Colour bar, vertically centred beside the mesh.
  const double scale = options.millimetres ? 1000.0 : 1.0;
  const int bar_height = std::max(40, view.area.height * 3 / 5);
  drawColorBar(&image, options.width - kBarAreaWidth + 16,
               top + (view.area.height - bar_height) / 2, 22, bar_height, 0.0,
               options.max_error_m * scale, options.millimetres ? "mm" : "m");
  if (!options.title.empty()) {
    cv::Mat canvas(image.height, image.width, CV_8UC3, image.data.data());  // RGB
    int baseline = 0;
    const cv::Size size =
        cv::getTextSize(options.title, cv::FONT_HERSHEY_SIMPLEX, 0.6, 1, &baseline);
    cv::putText(canvas, options.title, cv::Point((options.width - size.width) / 2, 26),
                cv::FONT_HERSHEY_SIMPLEX, 0.6, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
  }
  return image;
}

bool writeMeshErrorPng(const std::string& path, const Mesh& mesh,
                       std::span<const double> vertex_errors_m,
                       const MeshErrorRenderConfig& options, std::string* error) {
  const std::optional<ColorImage> image = renderMeshError(mesh, vertex_errors_m, options, error);
  if (!image.has_value()) return false;
  return writeColorImagePng(path, *image, error);
}

}  // namespace cblox
