#include "drivers/sim/scene_mesh_loader.h"

#include <cmath>
#include <cstdio>
#include <limits>
#include <string>

#include <gtest/gtest.h>

#include "core/io/obj_io.h"
#include "core/io/ply_io.h"
#include "core/mesh/primitive_meshes.h"
#include "test/test_support/temp_dir.h"

namespace cblox {
namespace {

class SceneMeshLoader : public ::testing::Test {
 protected:
  std::string writeMeshObj(const std::string& name, const Mesh& mesh) const {
    const std::string p = dir_.file(name);
    std::string error;
    EXPECT_TRUE(writeObj(p, mesh, &error)) << error;
    return p;
  }

  std::string writeMeshPly(const std::string& name, const Mesh& mesh,
                           PlyFormat format = PlyFormat::kBinaryLittleEndian) const {
    const std::string p = dir_.file(name);
    std::string error;
    EXPECT_TRUE(writePly(p, mesh, format, &error)) << error;
    return p;
  }

  // Expects loadSceneMesh to fail with a message that starts with the path and contains every
  // fragment.
  static void expectRejected(const std::string& p, std::initializer_list<const char*> fragments,
                             const SceneMeshCheck& options = {}) {
    std::string error;
    SceneMeshReport report;
    report.vertices = 12345;
    EXPECT_FALSE(loadSceneMesh(p, options, &error, &report).has_value()) << p;
    EXPECT_EQ(error.rfind(p, 0), 0u) << "expected the path first: " << error;
    for (const char* f : fragments) EXPECT_NE(error.find(f), std::string::npos) << error;
    EXPECT_EQ(report.vertices, 12345u) << "report written on failure";
    std::printf("  rejected: %s\n", error.c_str());
  }

  test::TempDir dir_{"cblox_scene_mesh"};
};

// A closed, coloured scene: a box and a sphere (both closed 2-manifolds).
Mesh sceneMesh() {
  Mesh m;
  appendBox(&m, Eigen::AlignedBox3f(Eigen::Vector3f(-1, -1, 0), Eigen::Vector3f(1, 2, 1.5f)),
            Color{180, 40, 20});
  appendSphere(&m, Eigen::Vector3f(3, 0, 1), 0.5f, 6, 10, Color{20, 90, 200});
  return m;
}

// A box (triangles 0-11) followed by three triangles sharing the edge between two new vertices
// a and b (a "fin" of three blades): one non-manifold edge.
Mesh meshWithFins() {
  Mesh m;
  appendBox(&m, Eigen::AlignedBox3f(Eigen::Vector3f(0, 0, 0), Eigen::Vector3f(1, 1, 1)),
            Color{100, 100, 100});
  const int a = static_cast<int>(m.numVertices());
  m.vertices.insert(m.vertices.end(),
                    {{5, 0, 0}, {5, 0, 1}, {6, 0, 0.5f}, {5, 1, 0.5f}, {4, -1, 0.5f}});
  m.colors.resize(m.numVertices(), Color{1, 2, 3});
  for (int apex = a + 2; apex < a + 5; ++apex) m.triangles.emplace_back(a, a + 1, apex);
  return m;
}

TEST_F(SceneMeshLoader, LoadsPlyAndObjByExtensionInAnyCase) {
  const Mesh mesh = sceneMesh();
  const std::string files[] = {writeMeshPly("scene.ply", mesh),
                               writeMeshPly("scene_ascii.PLY", mesh, PlyFormat::kAscii),
                               writeMeshObj("scene.obj", mesh), writeMeshObj("SCENE.Obj", mesh)};
  for (const std::string& p : files) {
    SCOPED_TRACE(p);
    std::string error;
    SceneMeshReport report;
    const std::optional<Mesh> loaded = loadSceneMesh(p, {}, &error, &report);
    ASSERT_TRUE(loaded.has_value()) << error;
    EXPECT_TRUE(loaded->vertices == mesh.vertices);
    EXPECT_TRUE(loaded->triangles == mesh.triangles);
    EXPECT_TRUE(loaded->colors == mesh.colors);
    EXPECT_EQ(report.vertices, mesh.numVertices());
    EXPECT_EQ(report.triangles, mesh.numTriangles());
    EXPECT_EQ(report.dropped_degenerate, 0u);
    EXPECT_EQ(report.boundary_edges, 0u);
    EXPECT_EQ(report.non_manifold_edges, 0u);
    EXPECT_TRUE(report.had_colors);
  }
  // The report is optional.
  EXPECT_TRUE(loadSceneMesh(files[0], {}, nullptr).has_value());
}

TEST_F(SceneMeshLoader, ColourlessMeshGetsUniformLightGrey) {
  Mesh mesh = sceneMesh();
  mesh.colors.clear();
  for (const std::string& p : {writeMeshObj("grey.obj", mesh), writeMeshPly("grey.ply", mesh)}) {
    std::string error;
    SceneMeshReport report;
    const std::optional<Mesh> loaded = loadSceneMesh(p, {}, &error, &report);
    ASSERT_TRUE(loaded.has_value()) << error;
    ASSERT_EQ(loaded->colors.size(), mesh.numVertices());
    for (const Color& c : loaded->colors) EXPECT_EQ(c, (Color{200, 200, 200}));
    EXPECT_FALSE(report.had_colors);
    EXPECT_EQ(loaded->validate(), "");
  }
  SceneMeshCheck options;
  options.default_color = Color{10, 20, 30};
  const std::optional<Mesh> loaded = loadSceneMesh(dir_.file("grey.obj"), options, nullptr);
  ASSERT_TRUE(loaded.has_value());
  EXPECT_EQ(loaded->colors.back(), (Color{10, 20, 30}));
}

TEST_F(SceneMeshLoader, DropsAndReportsDegenerateTriangles) {
  Mesh mesh = sceneMesh();
  const size_t good = mesh.numTriangles();
  mesh.triangles.emplace_back(0, 0, 1);  // repeated index
  mesh.vertices.insert(mesh.vertices.end(), {{0, 0, 5}, {1, 1, 5}, {2, 2, 5}});
  mesh.colors.resize(mesh.numVertices(), Color{0, 0, 0});
  const int n = static_cast<int>(mesh.numVertices());
  mesh.triangles.emplace_back(n - 3, n - 2, n - 1);    // collinear: zero area
  std::swap(mesh.triangles[3], mesh.triangles[good]);  // one of them in the middle
  for (const std::string& p : {writeMeshObj("d.obj", mesh), writeMeshPly("d.ply", mesh)}) {
    std::string error;
    SceneMeshReport report;
    const std::optional<Mesh> loaded = loadSceneMesh(p, {}, &error, &report);
    ASSERT_TRUE(loaded.has_value()) << error;
    EXPECT_EQ(loaded->numTriangles(), good);
    EXPECT_EQ(report.triangles, good);
    EXPECT_EQ(report.dropped_degenerate, 2u);
    EXPECT_EQ(report.vertices, mesh.numVertices());
    EXPECT_EQ(report.boundary_edges, 0u);
    EXPECT_EQ(report.non_manifold_edges, 0u);
    // The kept triangles stay in file order: slot 3 held a degenerate one.
    EXPECT_EQ(loaded->triangles[2], mesh.triangles[2]);
    EXPECT_EQ(loaded->triangles[3], mesh.triangles[4]);
    EXPECT_EQ(loaded->triangles.back(), mesh.triangles[good]);
  }
  // Nothing left: rejected.
  Mesh flat;
  flat.vertices = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}};
  flat.triangles = {{0, 1, 2}, {0, 0, 1}};
  expectRejected(writeMeshObj("flat.obj", flat), {"all 2 triangles are degenerate"});
}

// Strict check (allow_non_manifold = false): non-manifold meshes are refused.
SceneMeshCheck strictCheck() {
  SceneMeshCheck options;
  options.allow_non_manifold = false;
  return options;
}

TEST_F(SceneMeshLoader, StrictCheckRejectsNonManifoldMeshNamingTheTriangle) {
  const Mesh fins = meshWithFins();
  expectRejected(writeMeshObj("fins.obj", fins),
                 {"1 non-manifold edge(s)", "first is on triangle 12", "allow_non_manifold"},
                 strictCheck());
  // With a dropped degenerate triangle before the fins, the index still counts file triangles.
  Mesh shifted = fins;
  shifted.triangles.insert(shifted.triangles.begin() + 5, Eigen::Vector3i(1, 1, 2));
  expectRejected(writeMeshPly("fins.ply", shifted), {"first is on triangle 13"}, strictCheck());
  // Polygons count after triangulation: a quad before the fins is two triangles.
  expectRejected(dir_.write("quad_fins.obj",
                            "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
                            "v 5 0 0\nv 5 0 1\nv 6 0 0.5\nv 5 1 0.5\nv 4 -1 0.5\n"
                            "f 1 2 3 4\nf 5 6 7\nf 5 6 8\nf 5 6 9\n"),
                 {"first is on triangle 2"}, strictCheck());
}

TEST_F(SceneMeshLoader, AcceptsNonManifoldMeshByDefaultWithAWarning) {
  EXPECT_TRUE(SceneMeshCheck{}.allow_non_manifold);
  const std::string p = writeMeshObj("fins.obj", meshWithFins());
  std::string error;
  SceneMeshReport report;
  const std::optional<Mesh> loaded = loadSceneMesh(p, {}, &error, &report);
  ASSERT_TRUE(loaded.has_value()) << error;
  EXPECT_EQ(report.non_manifold_edges, 1u);
  EXPECT_EQ(report.boundary_edges, 6u);  // two free edges per blade
  EXPECT_EQ(report.triangles, 15u);
  ASSERT_EQ(report.warnings.size(), 1u);
  const std::string& warning = report.warnings[0];
  EXPECT_EQ(warning.rfind(p + ": ", 0), 0u) << warning;
  EXPECT_NE(warning.find("1 non-manifold edge(s)"), std::string::npos) << warning;
  EXPECT_NE(warning.find("first is on triangle 12"), std::string::npos) << warning;
  std::printf("  warning: %s\n", warning.c_str());
}

TEST_F(SceneMeshLoader, AcceptsDoubleSidedScanByDefault) {
  // A double-sided quad, as scanners export thin surfaces: front faces (0 1 2), (0 2 3) and
  // the same faces reversed. The diagonal 0-2 is used by four triangles: one non-manifold
  // edge; the rim edges each by two (front and back).
  const std::string p = dir_.write("double_sided.obj",
                                   "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
                                   "f 1 2 3\nf 1 3 4\nf 1 3 2\nf 1 4 3\n");
  std::string error;
  SceneMeshReport report;
  const std::optional<Mesh> loaded = loadSceneMesh(p, {}, &error, &report);
  ASSERT_TRUE(loaded.has_value()) << error;
  EXPECT_EQ(loaded->numTriangles(), 4u);
  EXPECT_EQ(report.non_manifold_edges, 1u);
  EXPECT_EQ(report.boundary_edges, 0u);
  ASSERT_EQ(report.warnings.size(), 1u);
  EXPECT_NE(report.warnings[0].find("1 non-manifold edge(s)"), std::string::npos)
      << report.warnings[0];
  EXPECT_NE(report.warnings[0].find("first is on triangle 0"), std::string::npos)
      << report.warnings[0];
  // The strict check refuses it.
  expectRejected(p, {"1 non-manifold edge(s)"}, strictCheck());
  // A manifold mesh has no warning.
  SceneMeshReport clean;
  ASSERT_TRUE(loadSceneMesh(writeMeshPly("scene.ply", sceneMesh()), {}, &error, &clean));
  EXPECT_TRUE(clean.warnings.empty());
}

TEST_F(SceneMeshLoader, RejectsEmptyFilesAndPointClouds) {
  expectRejected(dir_.write("empty.obj", ""), {"no vertices and no triangles"});
  expectRejected(dir_.write("comments.obj", "# nothing here\n\n"),
                 {"no vertices and no triangles"});
  expectRejected(dir_.write("empty.ply", ""), {"empty"});
  Mesh cloud = sceneMesh();
  cloud.triangles.clear();
  const std::string n = std::to_string(cloud.numVertices());
  expectRejected(writeMeshPly("cloud.ply", cloud),
                 {"point cloud", (n + " vertices, no faces").c_str(), "needs triangles"});
  expectRejected(writeMeshObj("cloud.obj", cloud), {"point cloud"});
}

TEST_F(SceneMeshLoader, RejectsNonFiniteVertices) {
  Mesh mesh = sceneMesh();
  mesh.vertices[3].y() = std::numeric_limits<float>::quiet_NaN();
  expectRejected(writeMeshPly("nan.ply", mesh), {"vertex 3 (0-based) is not finite", "nan"});
  expectRejected(writeMeshObj("nan.obj", mesh), {"vertex 3 (0-based) is not finite"});
  mesh = sceneMesh();
  mesh.vertices.back().z() = -std::numeric_limits<float>::infinity();
  expectRejected(writeMeshObj("inf.obj", mesh), {"is not finite", "inf"});
}

TEST_F(SceneMeshLoader, RejectsUnknownExtensionsMissingAndMalformedFiles) {
  const std::string stl = dir_.write("scene.stl", "solid x\nendsolid x\n");
  expectRejected(stl, {"extension '.stl'", "expected .ply or .obj"});
  expectRejected(dir_.write("scene", "v 0 0 0\n"), {"no extension", "expected .ply or .obj"});
  expectRejected(dir_.write("scene.obj.gz", ""), {"extension '.gz'"});
  expectRejected(dir_.file("missing.obj"), {"cannot open for reading"});
  expectRejected(dir_.file("missing.ply"), {"cannot open for reading"});
  // The reader's message, with its line, is passed on.
  const std::string bad = dir_.write("bad.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n");
  expectRejected(bad, {(bad + ":4: ").c_str(), "vertex index 9 is out of range"});
  expectRejected(dir_.write("bad.ply", "ply\nformat ascii 1.0\nend_header\n"),
                 {"no 'vertex' element"});
}

}  // namespace
}  // namespace cblox
