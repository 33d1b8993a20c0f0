#include "core/eval/mesh_accuracy.h"

#include <cmath>
#include <limits>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "core/mesh/primitive_meshes.h"
#include "core/tsdf/tsdf_layer.h"

namespace cblox {
namespace {

constexpr double kTolerance = 1e-6;
const Color kGrey{128, 128, 128};

// The square [-1, 1]^2 at height z, normal +z, split into cells x cells quads.
Mesh plane(float z, int cells = 20) {
  Mesh mesh;
  appendQuad(&mesh, Eigen::Vector3f(-1, -1, z), Eigen::Vector3f(2, 0, 0), Eigen::Vector3f(0, 2, 0),
             kGrey, cells, cells);
  return mesh;
}

Mesh sphere() {
  Mesh mesh;
  appendSphere(&mesh, Eigen::Vector3f(0.5f, -0.2f, 1.0f), 0.4f, 16, 32, kGrey);
  return mesh;
}

std::unique_ptr<TriangleMeshRaycaster> raycaster(const Mesh& mesh) {
  std::string error;
  auto result = TriangleMeshRaycaster::create(mesh, &error);
  EXPECT_NE(result, nullptr) << error;
  return result;
}

MeshAccuracy evaluate(const Mesh& truth, const Mesh& reconstruction,
                      const MeshAccuracyConfig& options = {}) {
  const auto gt = raycaster(truth);
  std::string error;
  const std::optional<MeshAccuracy> result =
      evaluateMeshAccuracy(*gt, reconstruction, options, &error);
  EXPECT_TRUE(result.has_value()) << error;
  return result.value_or(MeshAccuracy{});
}

void expectAllStatistics(const ErrorStatistics& s, double value, double tolerance) {
  EXPECT_NEAR(s.rmse, value, tolerance);
  EXPECT_NEAR(s.mean, value, tolerance);
  EXPECT_NEAR(s.median, value, tolerance);
  EXPECT_NEAR(s.p90, value, tolerance);
  EXPECT_NEAR(s.min, value, tolerance);
  EXPECT_NEAR(s.max, value, tolerance);
  EXPECT_NEAR(s.stddev, 0.0, tolerance);
}

TEST(MeshAccuracyTest, MeshAgainstItselfIsZeroAndComplete) {
  for (const Mesh& mesh : {sphere(), plane(0.3f)}) {
    const MeshAccuracy result = evaluate(mesh, mesh);
    EXPECT_EQ(result.reconstruction_vertices, mesh.numVertices());
    EXPECT_EQ(result.accuracy_m.count, mesh.numVertices());
    EXPECT_EQ(result.outlier_vertices, 0u);
    ASSERT_EQ(result.vertex_errors_m.size(), mesh.numVertices());
    for (const double e : result.vertex_errors_m) EXPECT_LE(e, kTolerance);
    expectAllStatistics(result.accuracy_m, 0.0, kTolerance);
    EXPECT_EQ(result.completeness, 1.0);
    EXPECT_EQ(result.precision, 1.0);
    EXPECT_EQ(result.f_score, 1.0);
    EXPECT_EQ(result.completeness_reference, "triangles");
  }
  Mesh box;
  appendBox(&box, Eigen::AlignedBox3f(Eigen::Vector3f(-1, -2, 0), Eigen::Vector3f(3, 1, 2.5f)),
            kGrey, /*inward=*/true);
  const MeshAccuracy result = evaluate(box, box);
  expectAllStatistics(result.accuracy_m, 0.0, kTolerance);
  EXPECT_EQ(result.completeness, 1.0);
}

TEST(MeshAccuracyTest, PlaneOffsetByDHasErrorD) {
  constexpr double d = 0.03;
  const Mesh truth = plane(0.0f);
  const Mesh offset = plane(static_cast<float>(d), 7);  // other vertices than the truth
  MeshAccuracyConfig options;
  options.completeness_threshold_m = 0.05;
  MeshAccuracy result = evaluate(truth, offset, options);
  expectAllStatistics(result.accuracy_m, d, kTolerance);
  for (const double e : result.vertex_errors_m) EXPECT_NEAR(e, d, kTolerance);
  EXPECT_EQ(result.completeness, 1.0);
  EXPECT_EQ(result.precision, 1.0);
  // 4 m^2 at 2 cm spacing: 10000 samples.
  EXPECT_EQ(result.ground_truth_samples, 10000u);
  EXPECT_NEAR(result.sample_spacing_m, 0.02, 1e-9);
  EXPECT_NEAR(result.ground_truth_area_m2, 4.0, 1e-9);

  options.completeness_threshold_m = 0.02;
  result = evaluate(truth, offset, options);
  expectAllStatistics(result.accuracy_m, d, kTolerance);
  EXPECT_EQ(result.completeness, 0.0);
  EXPECT_EQ(result.precision, 0.0);
  EXPECT_EQ(result.f_score, 0.0);

  // Offset below the plane: distances are unsigned.
  result = evaluate(truth, plane(static_cast<float>(-d), 3));
  expectAllStatistics(result.accuracy_m, d, kTolerance);
}

TEST(MeshAccuracyTest, HalfReconstructionIsHalfComplete) {
  const Mesh truth = plane(0.0f);
  Mesh half;  // x in [-1, 0]
  appendQuad(&half, Eigen::Vector3f(-1, -1, 0), Eigen::Vector3f(1, 0, 0), Eigen::Vector3f(0, 2, 0),
             kGrey, 10, 20);
  MeshAccuracyConfig options;
  options.completeness_threshold_m = 0.01;
  const MeshAccuracy result = evaluate(truth, half, options);
  expectAllStatistics(result.accuracy_m, 0.0, kTolerance);
  // Samples with x <= 0.01 are covered: (1 + 0.01) / 2 of the area. Stratified sampling keeps
  // the share within a few samples of that.
  EXPECT_NEAR(result.completeness, 0.505, 0.01);
  EXPECT_NEAR(result.completeness, 0.5, 0.05);
  EXPECT_EQ(result.precision, 1.0);
  EXPECT_NEAR(result.f_score, 2.0 * result.completeness / (1.0 + result.completeness), 1e-12);
}

TEST(MeshAccuracyTest, PointCloudReconstructionUsesNearestVertex) {
  const Mesh truth = plane(0.0f);
  Mesh cloud;  // a 2 cm grid 3 cm above the plane, no triangles
  for (int i = 0; i <= 100; ++i) {
    for (int j = 0; j <= 100; ++j) {
      cloud.vertices.emplace_back(-1.0f + 0.02f * i, -1.0f + 0.02f * j, 0.03f);
    }
  }
  MeshAccuracyConfig options;
  options.completeness_threshold_m = 0.05;  // sample to vertex <= sqrt(0.03^2 + 2 * 0.01^2)
  MeshAccuracy result = evaluate(truth, cloud, options);
  EXPECT_EQ(result.completeness_reference, "vertices");
  expectAllStatistics(result.accuracy_m, 0.03, kTolerance);
  EXPECT_EQ(result.completeness, 1.0);
  options.completeness_threshold_m = 0.025;  // every sample is >= 0.03 from the cloud
  result = evaluate(truth, cloud, options);
  EXPECT_EQ(result.completeness, 0.0);
  // Only the left half of the cloud: about half complete.
  Mesh half;
  for (const Eigen::Vector3f& v : cloud.vertices) {
    if (v.x() < 0.0f) half.vertices.push_back(v);
  }
  options.completeness_threshold_m = 0.04;
  result = evaluate(truth, half, options);
  EXPECT_NEAR(result.completeness, 0.5, 0.05);
}

TEST(MeshAccuracyTest, AlignmentIsAppliedToTheReconstructionFirst) {
  const Mesh truth = sphere();
  // The reconstruction lives in frame R: p_R = (R^T (p_G - t)) / s.
  Alignment T_G_R;
  T_G_R.T_A_B = Transformationd(
      Eigen::Quaterniond(Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized())),
      Eigen::Vector3d(0.4, -1.0, 2.0));
  for (const double scale : {1.0, 2.5}) {
    T_G_R.scale = scale;
    Mesh reconstruction = truth;
    for (Eigen::Vector3f& v : reconstruction.vertices) {
      v = (T_G_R.T_A_B.rotation().conjugate() * (v.cast<double>() - T_G_R.T_A_B.translation()) /
           scale)
              .cast<float>();
    }
    MeshAccuracyConfig options;
    const MeshAccuracy unaligned = evaluate(truth, reconstruction, options);
    EXPECT_GT(unaligned.accuracy_m.rmse, 0.1);
    options.T_G_R = T_G_R;
    const MeshAccuracy aligned = evaluate(truth, reconstruction, options);
    EXPECT_LE(aligned.accuracy_m.max, 1e-5) << "scale " << scale;
    EXPECT_EQ(aligned.completeness, 1.0);
    ASSERT_TRUE(aligned.T_G_R.has_value());
    EXPECT_EQ(aligned.T_G_R->scale, scale);
    // alignMesh() maps the reconstruction back onto the truth.
    const Mesh back = alignMesh(reconstruction, T_G_R);
    for (size_t i = 0; i < back.vertices.size(); ++i) {
      EXPECT_LE((back.vertices[i] - truth.vertices[i]).norm(), 1e-5f) << i;
    }
  }
}

TEST(MeshAccuracyTest, VerticesBeyondMaxDistanceAreOutliers) {
  const Mesh truth = plane(0.0f);
  Mesh reconstruction = plane(0.01f, 4);  // 25 vertices at 1 cm
  const size_t inliers = reconstruction.numVertices();
  reconstruction.vertices.emplace_back(0.0f, 0.0f, 1.0f);   // 1 m above
  reconstruction.vertices.emplace_back(0.5f, 0.0f, -2.0f);  // 2 m below
  reconstruction.colors.resize(reconstruction.vertices.size(), kGrey);
  MeshAccuracyConfig options;
  MeshAccuracy result = evaluate(truth, reconstruction, options);
  EXPECT_EQ(result.outlier_vertices, 0u);
  EXPECT_NEAR(result.accuracy_m.max, 2.0, kTolerance);

  options.max_distance_m = 0.5;
  result = evaluate(truth, reconstruction, options);
  EXPECT_EQ(result.outlier_vertices, 2u);
  EXPECT_EQ(result.accuracy_m.count, inliers);
  expectAllStatistics(result.accuracy_m, 0.01, kTolerance);
  EXPECT_TRUE(std::isinf(result.vertex_errors_m[inliers]));
  EXPECT_TRUE(std::isinf(result.vertex_errors_m[inliers + 1]));
  // Outliers count against precision.
  EXPECT_NEAR(result.precision, static_cast<double>(inliers) / (inliers + 2), 1e-12);
}

TEST(MeshAccuracyTest, ResultsDoNotDependOnThreadsAndAreDeterministic) {
  const Mesh truth = sphere();
  Mesh reconstruction = sphere();
  std::mt19937 rng(7);
  std::normal_distribution<float> noise(0.0f, 0.01f);
  for (Eigen::Vector3f& v : reconstruction.vertices)
    v += Eigen::Vector3f(noise(rng), noise(rng), 0);
  MeshAccuracyConfig options;
  options.completeness_threshold_m = 0.01;
  options.surface_sample_spacing_m = 0.01;
  options.num_threads = 1;
  const MeshAccuracy one = evaluate(truth, reconstruction, options);
  options.num_threads = 3;
  const MeshAccuracy three = evaluate(truth, reconstruction, options);
  EXPECT_EQ(one.vertex_errors_m, three.vertex_errors_m);
  EXPECT_EQ(one.accuracy_m.rmse, three.accuracy_m.rmse);
  EXPECT_EQ(one.completeness, three.completeness);
  EXPECT_GT(one.completeness, 0.0);
  EXPECT_LT(one.completeness, 1.0);
  options.seed = 99;  // other samples, about the same completeness
  const MeshAccuracy reseeded = evaluate(truth, reconstruction, options);
  EXPECT_NEAR(reseeded.completeness, one.completeness, 0.05);
}

TEST(MeshAccuracyTest, SampleCountIsCapped) {
  MeshAccuracyConfig options;
  options.surface_sample_spacing_m = 0.001;  // would be 4 million samples
  options.max_surface_samples = 5000;
  const MeshAccuracy result = evaluate(plane(0.0f), plane(0.0f), options);
  EXPECT_EQ(result.ground_truth_samples, 5000u);
  EXPECT_NEAR(result.sample_spacing_m, std::sqrt(4.0 / 5000), 1e-12);
}

TEST(MeshAccuracyTest, RejectsBadInputWithMessages) {
  const auto gt = raycaster(plane(0.0f));
  const Mesh good = plane(0.0f, 2);
  std::string error;
  EXPECT_FALSE(evaluateMeshAccuracy(*gt, Mesh{}, {}, &error).has_value());
  EXPECT_NE(error.find("no vertex"), std::string::npos) << error;

  const auto expectOptionError = [&](MeshAccuracyConfig options, const std::string& field) {
    std::string message;
    EXPECT_FALSE(options.validate().empty()) << field;
    EXPECT_FALSE(evaluateMeshAccuracy(*gt, good, options, &message).has_value()) << field;
    EXPECT_NE(message.find(field), std::string::npos) << message;
  };
  MeshAccuracyConfig options;
  EXPECT_EQ(options.validate(), "");
  options.completeness_threshold_m = 0.0;
  expectOptionError(options, "completeness_threshold_m");
  options = {};
  options.surface_sample_spacing_m = std::numeric_limits<double>::quiet_NaN();
  expectOptionError(options, "surface_sample_spacing_m");
  options = {};
  options.max_surface_samples = 0;
  expectOptionError(options, "max_surface_samples");
  options = {};
  options.max_distance_m = -1.0;
  expectOptionError(options, "max_distance_m");
  options = {};
  options.num_threads = 0;
  expectOptionError(options, "num_threads");
  options = {};
  options.T_G_R = Alignment{Transformationd(), 0.0};
  expectOptionError(options, "T_G_R.scale");

  Mesh bad = good;
  bad.triangles.push_back(Eigen::Vector3i(0, 1, 1000));
  EXPECT_FALSE(evaluateMeshAccuracy(*gt, bad, {}, &error).has_value());
  EXPECT_NE(error.find("malformed"), std::string::npos) << error;
  bad = good;
  bad.vertices[3].x() = std::numeric_limits<float>::infinity();
  EXPECT_FALSE(evaluateMeshAccuracy(*gt, bad, {}, &error).has_value());
  EXPECT_NE(error.find("vertex 3 is not finite"), std::string::npos) << error;

  // A ground truth of degenerate triangles has no area to sample.
  Mesh flat;
  flat.vertices = {Eigen::Vector3f(0, 0, 0), Eigen::Vector3f(1, 0, 0), Eigen::Vector3f(2, 0, 0)};
  flat.triangles = {Eigen::Vector3i(0, 1, 2)};
  const auto degenerate = raycaster(flat);
  EXPECT_FALSE(evaluateMeshAccuracy(*degenerate, good, {}, &error).has_value());
  EXPECT_NE(error.find("no surface area"), std::string::npos) << error;
}

// The keys of a JSON object, in its order.
std::vector<std::string> keysOf(const nlohmann::ordered_json& object) {
  std::vector<std::string> keys;
  for (const auto& item : object.items()) keys.push_back(item.key());
  return keys;
}

TEST(MeshAccuracyTest, JsonHasAllKeys) {
  MeshAccuracyConfig options;
  options.T_G_R = Alignment{Transformationd(), 1.0};
  const MeshAccuracy result = evaluate(plane(0.0f), plane(0.03f, 4), options);
  const nlohmann::ordered_json json = result.toJson();
  using Keys = std::vector<std::string>;
  EXPECT_EQ(keysOf(json), (Keys{"reconstruction_vertices", "reconstruction_triangles",
                                "ground_truth_triangles", "ground_truth_area_m2", "alignment",
                                "max_distance_m", "accuracy", "completeness"}));
  EXPECT_EQ(keysOf(json.at("alignment")),
            (Keys{"applied", "scale", "rotation_xyzw", "translation_m"}));
  EXPECT_EQ(keysOf(json.at("accuracy")), (Keys{"vertices", "outlier_vertices", "rmse_m", "mean_m",
                                               "median_m", "p90_m", "std_m", "min_m", "max_m"}));
  EXPECT_EQ(keysOf(json.at("completeness")),
            (Keys{"threshold_m", "ground_truth_samples", "sample_spacing_m", "reference",
                  "completeness", "precision", "f_score"}));
  // Counts are unsigned integers, measures doubles.
  for (const nlohmann::ordered_json& count :
       {json.at("reconstruction_vertices"), json.at("reconstruction_triangles"),
        json.at("ground_truth_triangles"), json.at("accuracy").at("vertices"),
        json.at("accuracy").at("outlier_vertices"),
        json.at("completeness").at("ground_truth_samples")}) {
    EXPECT_TRUE(count.is_number_unsigned()) << count;
  }
  EXPECT_EQ(json.at("reconstruction_vertices"), 25u);
  EXPECT_EQ(json.at("reconstruction_triangles"), 32u);
  EXPECT_EQ(json.at("ground_truth_triangles"), 800u);
  EXPECT_TRUE(json.at("ground_truth_area_m2").is_number_float());
  EXPECT_NEAR(json.at("ground_truth_area_m2").get<double>(), 4.0, kTolerance);
  EXPECT_EQ(json.at("alignment"), (nlohmann::ordered_json{{"applied", true},
                                                          {"scale", 1.0},
                                                          {"rotation_xyzw", {0.0, 0.0, 0.0, 1.0}},
                                                          {"translation_m", {0.0, 0.0, 0.0}}}));
  EXPECT_EQ(json.at("accuracy").at("vertices"), 25u);
  EXPECT_EQ(json.at("accuracy").at("outlier_vertices"), 0u);
  EXPECT_NEAR(json.at("accuracy").at("median_m").get<double>(), 0.03, kTolerance);
  const nlohmann::ordered_json& c = json.at("completeness");
  EXPECT_EQ(c.at("threshold_m"), 0.05);
  EXPECT_EQ(c.at("ground_truth_samples"), 10000u);
  EXPECT_EQ(c.at("sample_spacing_m"), 0.02);
  EXPECT_EQ(c.at("reference"), "triangles");
  for (const char* key : {"completeness", "precision", "f_score"}) {
    EXPECT_TRUE(c.at(key).is_number_float()) << key;
    EXPECT_EQ(c.at(key), 1.0) << key;
  }
  // As written: the infinite max_distance_m (no outlier bound) becomes null, JSON having no
  // infinity; every other number reads back exactly.
  const nlohmann::ordered_json written = nlohmann::ordered_json::parse(json.dump(2));
  EXPECT_TRUE(written.at("max_distance_m").is_null());
  nlohmann::ordered_json finite = json;
  finite["max_distance_m"] = nullptr;
  EXPECT_EQ(written, finite);
}

TEST(SurfaceBlocksTest, CountsBlocksHoldingVerticesLikeTsdfLayer) {
  LayerConfig grid;
  grid.voxel_size = 0.1f;
  grid.voxels_per_side = 2;  // blocks of 0.2 m
  Mesh mesh;
  mesh.vertices = {Eigen::Vector3f(0.05f, 0.05f, 0.05f), Eigen::Vector3f(0.15f, 0.1f, 0.1f),
                   Eigen::Vector3f(-0.01f, 0.0f, 0.0f), Eigen::Vector3f(0.5f, 0.5f, 0.5f)};
  std::string error;
  std::optional<SurfaceBlockCount> count = countSurfaceBlocks(mesh, grid, &error);
  ASSERT_TRUE(count.has_value()) << error;
  EXPECT_EQ(count->blocks, 3u);
  EXPECT_EQ(count->voxel_bytes, 3u * 8u * 12u);
  EXPECT_EQ(count->voxels_per_side, 2);
  EXPECT_EQ(count->voxel_size_m, 0.1);

  // The same blocks as a TsdfLayer allocates for these points.
  grid = LayerConfig{};
  const Mesh surface = sphere();
  count = countSurfaceBlocks(surface, grid, &error);
  ASSERT_TRUE(count.has_value()) << error;
  TsdfLayer layer(grid);
  for (const Eigen::Vector3f& v : surface.vertices)
    layer.allocateBlock(layer.blockIndexFromPoint(v));
  EXPECT_EQ(count->blocks, layer.numBlocks());
  EXPECT_EQ(count->voxel_bytes, layer.numBlocks() * 512u * 12u);

  grid.voxels_per_side = 3;
  EXPECT_FALSE(countSurfaceBlocks(surface, grid, &error).has_value());
  EXPECT_NE(error.find("voxels_per_side"), std::string::npos) << error;
  mesh.vertices[1].y() = std::numeric_limits<float>::quiet_NaN();
  EXPECT_FALSE(countSurfaceBlocks(mesh, LayerConfig{}, &error).has_value());
  EXPECT_NE(error.find("vertex 1 is not finite"), std::string::npos) << error;
}

}  // namespace
}  // namespace cblox
