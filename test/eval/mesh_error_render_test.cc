#include "core/eval/mesh_error_render.h"

#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "core/eval/colormap.h"
#include "core/mesh/primitive_meshes.h"
#include "test/test_support/temp_dir.h"

namespace cblox {
namespace {

const Color kGrey{128, 128, 128};

Mesh sphere() {
  Mesh mesh;
  appendSphere(&mesh, Eigen::Vector3f(1.0f, 2.0f, 0.5f), 0.5f, 24, 48, kGrey);
  return mesh;
}

// Errors growing with height: 0 at the bottom of the sphere, 0.06 m at the top.
std::vector<double> heightErrors(const Mesh& mesh) {
  std::vector<double> errors;
  for (const Eigen::Vector3f& v : mesh.vertices) errors.push_back(0.06 * (v.z() - 0.0f));
  return errors;
}

// Pixels of exactly `color` in the RGB image, in columns [u_begin, u_end) and rows
// [v_begin, height).
int countColor(const ColorImage& image, const Color& color, int u_begin, int u_end,
               int v_begin = 0) {
  int count = 0;
  for (int v = v_begin; v < image.height; ++v) {
    for (int u = u_begin; u < u_end; ++u) count += image(u, v) == color ? 1 : 0;
  }
  return count;
}

// True when every channel differs by at most `tolerance`.
bool near(const Color& a, const Color& b, int tolerance) {
  return std::abs(a.r - b.r) <= tolerance && std::abs(a.g - b.g) <= tolerance &&
         std::abs(a.b - b.b) <= tolerance;
}

TEST(MeshErrorRenderTest, WritesPngOfRequestedSizeWithColourBar) {
  const test::TempDir dir("cblox_err");
  const std::string path = dir.file("error.png");
  const Mesh mesh = sphere();
  MeshErrorRenderConfig options;
  options.width = 400;
  options.height = 300;
  options.title = "vertex error";
  std::string error;
  ASSERT_TRUE(writeMeshErrorPng(path, mesh, heightErrors(mesh), options, &error)) << error;
  const cv::Mat bgr = cv::imread(path, cv::IMREAD_COLOR);
  ASSERT_FALSE(bgr.empty());
  EXPECT_EQ(bgr.cols, 400);
  EXPECT_EQ(bgr.rows, 300);

  const std::optional<ColorImage> image =
      renderMeshError(mesh, heightErrors(mesh), options, &error);
  ASSERT_TRUE(image.has_value()) << error;
  // The colour bar (right of the mesh) holds both ends of the colour map.
  const int bar_begin = options.width - 110;
  EXPECT_GT(countColor(*image, colormap(1.0), bar_begin, options.width), 10);
  EXPECT_GT(countColor(*image, colormap(0.0), bar_begin, options.width), 10);
  // The mesh is drawn: many non-background pixels left of the bar, the corners of the
  // picture are background (the automatic view fits the whole sphere).
  const int background = countColor(*image, options.background, 0, bar_begin, 40);
  const int area = bar_begin * (options.height - 40);
  EXPECT_GT(area - background, area / 10);
  EXPECT_EQ((*image)(0, 40), options.background);
  EXPECT_EQ((*image)(bar_begin - 1, options.height - 1), options.background);
  for (int u = 0; u < bar_begin; ++u) {
    ASSERT_EQ((*image)(u, 40), options.background) << u;
    ASSERT_EQ((*image)(u, options.height - 1), options.background) << u;
  }
  for (int v = 40; v < options.height; ++v) {
    ASSERT_EQ((*image)(0, v), options.background) << v;
    ASSERT_EQ((*image)(bar_begin - 1, v), options.background) << v;
  }
}

TEST(MeshErrorRenderTest, ColourFollowsTheInterpolatedError) {
  // A flat quad facing the camera, error 0 everywhere or max everywhere: the centre pixel
  // is the colour map's end, shaded by the headlight (facing it: factor 1).
  Mesh quad;
  appendQuad(&quad, Eigen::Vector3f(-1, -1, 0), Eigen::Vector3f(2, 0, 0), Eigen::Vector3f(0, 2, 0),
             kGrey, 4, 4);
  MeshErrorRenderConfig options;
  options.width = 310;  // mesh area 200 x 200
  options.height = 200;
  options.viewpoint = MeshViewpoint{Eigen::Vector3d(0, 0, 3), Eigen::Vector3d(0, 0, 0)};
  std::string error;
  for (const double value : {0.0, 0.05, 1.0, std::numeric_limits<double>::infinity()}) {
    const std::vector<double> errors(quad.numVertices(), value);
    const std::optional<ColorImage> image = renderMeshError(quad, errors, options, &error);
    ASSERT_TRUE(image.has_value()) << error;
    EXPECT_EQ((*image)(100, 100), colormap(value / options.max_error_m)) << value;
  }
  // Vertices with x > 0 at max, the others at 0: the left half is dark, the right half rises
  // from dark at x = 0 to yellow at x = 0.5 (interpolated across the cells).
  std::vector<double> errors;
  for (const Eigen::Vector3f& v : quad.vertices) errors.push_back(v.x() > 0.0f ? 0.05 : 0.0);
  const std::optional<ColorImage> image = renderMeshError(quad, errors, options, &error);
  ASSERT_TRUE(image.has_value()) << error;
  // Off the image centre the headlight darkens the colour slightly (cos ~ 0.96 there).
  EXPECT_TRUE(near((*image)(30, 100), colormap(0.0), 6)) << (*image)(30, 100);
  EXPECT_TRUE(near((*image)(170, 100), colormap(1.0), 6)) << (*image)(170, 100);
  const Color middle = (*image)(100, 100);  // error 0 at x = 0: the middle is dark again
  EXPECT_TRUE(near(middle, colormap(0.0), 6)) << middle;
  const Color between = (*image)(120, 100);  // x ~ 0.25: half way to the max
  EXPECT_TRUE(near(between, colormap(0.5), 12)) << between;
}

TEST(MeshErrorRenderTest, BackFacesAreSeeThroughWhenCulled) {
  Mesh quad;  // normal +z, seen from below
  appendQuad(&quad, Eigen::Vector3f(-1, -1, 0), Eigen::Vector3f(2, 0, 0), Eigen::Vector3f(0, 2, 0),
             kGrey);
  const std::vector<double> errors(quad.numVertices(), 0.0);
  MeshErrorRenderConfig options;
  options.width = 310;
  options.height = 200;
  options.viewpoint = MeshViewpoint{Eigen::Vector3d(0, 0, -3), Eigen::Vector3d(0, 0, 0)};
  std::string error;
  std::optional<ColorImage> image = renderMeshError(quad, errors, options, &error);
  ASSERT_TRUE(image.has_value()) << error;
  EXPECT_EQ((*image)(100, 100), options.background);
  options.cull_back_faces = false;
  image = renderMeshError(quad, errors, options, &error);
  ASSERT_TRUE(image.has_value()) << error;
  EXPECT_EQ((*image)(100, 100), colormap(0.0));
}

TEST(MeshErrorRenderTest, AutomaticViewpointSeesTheBoxFromAboveAndTheSide) {
  const Eigen::AlignedBox3d box(Eigen::Vector3d(-1, -2, 0), Eigen::Vector3d(3, 1, 2));
  const MeshViewpoint view = automaticViewpoint(box, 45.0, 4.0 / 3.0);
  EXPECT_TRUE(view.look_at.isApprox(box.center()));
  const Eigen::Vector3d to_eye = view.eye - view.look_at;
  EXPECT_GT(to_eye.z(), 0.0);  // above
  EXPECT_GT(to_eye.x(), 0.0);  // from +x
  EXPECT_LT(to_eye.y(), 0.0);  // and -y
  EXPECT_NEAR(std::asin(to_eye.normalized().z()) * 180.0 / M_PI, 35.0, 1e-9);
  EXPECT_FALSE(box.contains(view.eye));
  // Degenerate boxes still give a usable view.
  const MeshViewpoint point = automaticViewpoint(
      Eigen::AlignedBox3d(Eigen::Vector3d(1, 1, 1), Eigen::Vector3d(1, 1, 1)), 45.0, 1.0);
  EXPECT_NEAR((point.eye - point.look_at).norm(), 1.0, 1e-12);
  const MeshViewpoint empty = automaticViewpoint(Eigen::AlignedBox3d(), 45.0, 1.0);
  EXPECT_TRUE(empty.eye.allFinite());
}

TEST(MeshErrorRenderTest, RejectsBadInputWithMessages) {
  const Mesh mesh = sphere();
  const std::vector<double> errors = heightErrors(mesh);
  std::string error;
  MeshErrorRenderConfig options;
  EXPECT_EQ(options.validate(), "");
  options.width = 50;
  EXPECT_FALSE(renderMeshError(mesh, errors, options, &error).has_value());
  EXPECT_NE(error.find("width"), std::string::npos) << error;
  options = {};
  options.max_error_m = 0.0;
  EXPECT_FALSE(renderMeshError(mesh, errors, options, &error).has_value());
  EXPECT_NE(error.find("max_error_m"), std::string::npos) << error;
  options = {};
  options.viewpoint = MeshViewpoint{Eigen::Vector3d(1, 1, 1), Eigen::Vector3d(1, 1, 1)};
  EXPECT_FALSE(renderMeshError(mesh, errors, options, &error).has_value());
  EXPECT_NE(error.find("coincide"), std::string::npos) << error;
  options = {};
  options.supersampling = 5;
  EXPECT_FALSE(options.validate().empty());

  EXPECT_FALSE(renderMeshError(mesh, std::vector<double>(3, 0.0), {}, &error).has_value());
  EXPECT_NE(error.find("3 vertex errors"), std::string::npos) << error;
  std::vector<double> negative = errors;
  negative[5] = -1.0;
  EXPECT_FALSE(renderMeshError(mesh, negative, {}, &error).has_value());
  EXPECT_NE(error.find("vertex 5"), std::string::npos) << error;
  Mesh cloud;
  cloud.vertices = {Eigen::Vector3f::Zero()};
  EXPECT_FALSE(renderMeshError(cloud, std::vector<double>(1, 0.0), {}, &error).has_value());
  EXPECT_FALSE(error.empty());
  EXPECT_FALSE(writeMeshErrorPng("/nonexistent-dir/x.png", mesh, errors, {}, &error));
  EXPECT_NE(error.find("/nonexistent-dir/x.png"), std::string::npos) << error;
}

}  // namespace
}  // namespace cblox
