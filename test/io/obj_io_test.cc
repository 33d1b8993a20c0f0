#include "core/io/obj_io.h"

#include <cstdint>
#include <cstdio>
#include <cstring>
#include <limits>
#include <random>
#include <string>

#include <gtest/gtest.h>

#include "test/test_support/awkward_mesh.h"
#include "test/test_support/temp_dir.h"

namespace cblox {
namespace {

class ObjIo : public ::testing::Test {
 protected:
  // Expects readObj to fail with a message that starts with "<path>:<line>: " and contains
  // every fragment, and to leave the mesh untouched.
  void expectReadError(const std::string& p, int line,
                       std::initializer_list<const char*> fragments) {
    Mesh mesh;
    mesh.vertices.emplace_back(1.0f, 2.0f, 3.0f);
    std::string error;
    EXPECT_FALSE(readObj(p, &mesh, &error)) << p;
    const std::string prefix = p + ":" + std::to_string(line) + ": ";
    EXPECT_EQ(error.rfind(prefix, 0), 0u) << "expected prefix '" << prefix << "': " << error;
    for (const char* f : fragments) EXPECT_NE(error.find(f), std::string::npos) << error;
    EXPECT_EQ(mesh.numVertices(), 1u) << "mesh changed on failure";
    std::printf("  rejected: %s\n", error.c_str());
  }

  test::TempDir dir_{"cblox_obj"};
};

// Awkward floats on purpose (see awkwardMesh), the same on every run.
Mesh testMesh(bool colors, size_t num_vertices = 200) {
  return test::awkwardMesh(11, colors, /*normals=*/false, num_vertices);
}

TEST_F(ObjIo, RoundTripIsExact) {
  for (const bool colors : {false, true}) {
    SCOPED_TRACE(colors ? "colours" : "no colours");
    const Mesh mesh = testMesh(colors);
    const std::string p = dir_.file("mesh.obj");
    std::string error;
    ASSERT_TRUE(writeObj(p, mesh, &error)) << error;
    Mesh back;
    ObjReadStats stats;
    ASSERT_TRUE(readObj(p, &back, &error, &stats)) << error;
    test::expectSameMesh(mesh, back);
    EXPECT_EQ(stats.vertices, mesh.numVertices());
    EXPECT_EQ(stats.faces, mesh.numTriangles());
    EXPECT_EQ(stats.triangles, mesh.numTriangles());
    EXPECT_EQ(stats.unknown_statements, 0u);
    EXPECT_FALSE(stats.colors_dropped);
  }
}

TEST_F(ObjIo, RoundTripKeepsEveryColourValueIncludingOnlyZeroAndFull) {
  // Every byte value survives c / 255 and back.
  Mesh all;
  for (int c = 0; c < 256; ++c) {
    all.vertices.emplace_back(static_cast<float>(c), 0.0f, 0.0f);
    const auto b = static_cast<uint8_t>(c);
    all.colors.push_back(Color{b, static_cast<uint8_t>(255 - c), b});
  }
  // Only 0 and 255: written as 0 and 1, which must not be read as 0-255 values.
  Mesh binary;
  binary.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  binary.colors = {Color{255, 0, 0}, Color{0, 255, 0}, Color{255, 255, 255}};
  binary.triangles = {{0, 1, 2}};
  for (const Mesh* mesh : {&all, &binary}) {
    const std::string p = dir_.file("c.obj");
    std::string error;
    ASSERT_TRUE(writeObj(p, *mesh, &error)) << error;
    Mesh back;
    ASSERT_TRUE(readObj(p, &back, &error)) << error;
    test::expectSameMesh(*mesh, back);
  }
}

TEST_F(ObjIo, WritesPlainObj) {
  Mesh m;
  m.vertices = {{0.5f, -1.0f, 2.0f}, {1.0f, 0.0f, 0.0f}, {0.0f, 0.25f, 0.0f}};
  m.triangles = {{0, 1, 2}, {2, 1, 0}};
  const std::string p = dir_.file("plain.obj");
  ASSERT_TRUE(writeObj(p, m, nullptr));
  EXPECT_EQ(test::readFile(p),
            "# written by cblox: 3 vertices, 2 triangles\n"
            "v 0.5 -1 2\nv 1 0 0\nv 0 0.25 0\nf 1 2 3\nf 3 2 1\n");
  m.colors = {Color{255, 0, 0}, Color{0, 255, 0}, Color{0, 0, 51}};
  m.normals = {{0, 0, 1}, {0, 0, 1}, {0, 0, 1}};  // not written
  ASSERT_TRUE(writeObj(p, m, nullptr));
  EXPECT_EQ(test::readFile(p),
            "# written by cblox: 3 vertices (with r g b colours in [0, 1]), 2 triangles\n"
            "v 0.5 -1 2 1 0 0\nv 1 0 0 0 1 0\nv 0 0.25 0 0 0 0.2\nf 1 2 3\nf 3 2 1\n");
  // An empty mesh is a valid (empty) file.
  ASSERT_TRUE(writeObj(p, Mesh{}, nullptr));
  Mesh back = m;
  ASSERT_TRUE(readObj(p, &back, nullptr));
  EXPECT_TRUE(back.empty());
}

TEST_F(ObjIo, ReadsHandWrittenObjWithQuadsNegativeIndicesAndCornerForms) {
  const std::string p = dir_.write("scene.obj",
                                   "# a hand-written file\r\n"
                                   "mtllib scene.mtl\r\n"
                                   "o box\r\n"
                                   "\r\n"
                                   "v 0 0 0 1 0 0\r\n"
                                   "v 1 0 0 0 1 0   # trailing comment\r\n"
                                   "v\t1 1 0\t0 0 1\r\n"
                                   "v 0 1 0 0.5 0.5 0.5\r\n"
                                   "vt 0 0\r\n"
                                   "vt 1 0 0\r\n"
                                   "vt 1\r\n"
                                   "vn 0 0 1\r\n"
                                   "g side\r\n"
                                   "usemtl red\r\n"
                                   "s off\r\n"
                                   "f 1 2 3 4\r\n"               // quad -> 2 triangles
                                   "f -4/1 -3/2 -2/3\r\n"        // relative, i/t
                                   "f 1//1 3//1 4//1\r\n"        // i//n
                                   "f +1/1/1 2/2/1 \\\r\n"       // i/t/n, continued
                                   "  3/3/1 4/1/1 -4/-3/-1\r\n"  // pentagon -> 3 triangles
                                   "v 2 0 0 0 0 0\n"             // LF only is fine too
                                   "f -1 -4 -5\n"                // relative to 5 vertices
                                   "curv 0.0 1.0 1 2\n"          // unknown: skipped
                                   "cstype bezier\n"             // unknown: skipped
                                   "l 1 2\n"
                                   "p 3\n"
                                   "vp 0.5\n"
                                   "f 5 1 2");  // no final newline
  Mesh m;
  std::string error;
  ObjReadStats stats;
  ASSERT_TRUE(readObj(p, &m, &error, &stats)) << error;
  ASSERT_EQ(m.numVertices(), 5u);
  EXPECT_EQ(m.vertices[2], Eigen::Vector3f(1, 1, 0));
  EXPECT_EQ(m.vertices[4], Eigen::Vector3f(2, 0, 0));
  ASSERT_EQ(m.colors.size(), 5u);
  EXPECT_EQ(m.colors[0], (Color{255, 0, 0}));
  EXPECT_EQ(m.colors[2], (Color{0, 0, 255}));
  EXPECT_EQ(m.colors[3], (Color{128, 128, 128}));
  EXPECT_EQ(m.colors[4], (Color{0, 0, 0}));
  EXPECT_TRUE(m.normals.empty());
  const std::vector<Eigen::Vector3i> expected = {
      {0, 1, 2}, {0, 2, 3},             // quad
      {0, 1, 2},                        // -4 -3 -2 with 4 vertices
      {0, 2, 3},                        // i//n
      {0, 1, 2}, {0, 2, 3}, {0, 3, 0},  // pentagon fan (the last corner repeats vertex 1)
      {4, 1, 0},                        // -1 -4 -5 with 5 vertices
      {4, 0, 1}};
  EXPECT_TRUE(m.triangles == expected) << m.numTriangles() << " triangles";
  EXPECT_EQ(stats.vertices, 5u);
  EXPECT_EQ(stats.faces, 6u);
  EXPECT_EQ(stats.triangles, 9u);
  EXPECT_EQ(stats.ignored_statements, 12u);  // mtllib o vt*3 vn g usemtl s l p vp
  EXPECT_EQ(stats.unknown_statements, 2u);
  EXPECT_EQ(stats.first_unknown_keyword, "curv");
  EXPECT_EQ(stats.first_unknown_line, 23);
  EXPECT_FALSE(stats.colors_dropped);
}

TEST_F(ObjIo, ColourScaleAndPartialColours) {
  // A value above 1 anywhere in the file makes every colour a 0-255 value.
  const std::string p = dir_.write("c255.obj",
                                   "v 0 0 0 1 0.5 0\n"
                                   "v 1 0 0 255 128 300\n"
                                   "v 0 1 0 -3 12.4 12.6\n"
                                   "f 1 2 3\n");
  Mesh m;
  std::string error;
  ASSERT_TRUE(readObj(p, &m, &error)) << error;
  ASSERT_EQ(m.colors.size(), 3u);
  EXPECT_EQ(m.colors[0], (Color{1, 1, 0}));  // 0.5 rounds half away from zero
  EXPECT_EQ(m.colors[1], (Color{255, 128, 255}));
  EXPECT_EQ(m.colors[2], (Color{0, 12, 13}));

  // Colours on some vertices only: dropped, and said so. `v x y z w` has no colour.
  const std::string q = dir_.write("partial.obj",
                                   "v 0 0 0 1 1 1\n"
                                   "v 1 0 0 1.0\n"
                                   "v 0 1 0\n"
                                   "f 1 2 3\n");
  ObjReadStats stats;
  ASSERT_TRUE(readObj(q, &m, &error, &stats)) << error;
  EXPECT_EQ(m.numVertices(), 3u);
  EXPECT_TRUE(m.colors.empty());
  EXPECT_TRUE(stats.colors_dropped);
  EXPECT_EQ(m.validate(), "");

  // Extreme but valid numbers: underflow becomes zero, nan/inf are passed on.
  const std::string r = dir_.write("extreme.obj", "v 1e-60 -1e-50 1e-40\nv nan inf -inf\n");
  ASSERT_TRUE(readObj(r, &m, &error)) << error;
  EXPECT_EQ(m.vertices[0].x(), 0.0f);
  EXPECT_EQ(m.vertices[0].y(), 0.0f);
  EXPECT_GT(m.vertices[0].z(), 0.0f);
  EXPECT_TRUE(std::isnan(m.vertices[1].x()));
  EXPECT_TRUE(std::isinf(m.vertices[1].y()));
}

TEST_F(ObjIo, RejectsMalformedStatementsWithFileAndLine) {
  const std::string tri = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
  // Numbers.
  expectReadError(dir_.write("a.obj", tri + "v 1 abc 3\n"), 4,
                  {"'v': expected a number for y, found 'abc'"});
  expectReadError(dir_.write("b.obj", "v 1 2 3e99\n"), 1, {"'v'", "z", "out of float range"});
  expectReadError(dir_.write("c.obj", "v 1 2\n"), 1,
                  {"expected 'v x y z [w]' or 'v x y z r g b', found 2 values"});
  expectReadError(dir_.write("d.obj", "v 1 2 3 4 5\n"), 1, {"found 5 values"});
  expectReadError(dir_.write("e.obj", "\n\nv 1 2 3 0 0 x\n"), 3,
                  {"expected a number for blue, found 'x'"});
  expectReadError(dir_.write("f.obj", "v 1 2 3 0 nan 0\n"), 1, {"colour", "green", "not finite"});
  expectReadError(dir_.write("g.obj", "v 1 2 3 1.5.1\n"), 1, {"for w, found '1.5.1'"});
  expectReadError(dir_.write("h.obj", "vt 0 0 0 0\n"), 1, {"expected 'vt u [v [w]]'", "found 4"});
  expectReadError(dir_.write("i.obj", "vn 0 0\n"), 1, {"expected 'vn x y z', found 2 values"});
  expectReadError(dir_.write("j.obj", "vn 0 0 one\n"), 1, {"'vn'", "found 'one'"});
  expectReadError(dir_.write("k.obj", "v 1 2 --3\n"), 1, {"found '--3'"});
  expectReadError(dir_.write("l.obj", "v 1 2 ++3\n"), 1, {"found '++3'"});
  // Faces.
  expectReadError(dir_.write("m.obj", tri + "f 1 2 0\n"), 4,
                  {"corner '0'", "vertex index 0 is invalid"});
  expectReadError(dir_.write("n.obj", tri + "f 1 2 4\n"), 4,
                  {"corner '4'", "vertex index 4 is out of range: 3 vertices defined so far"});
  expectReadError(dir_.write("o.obj", tri + "f -1 -2 -4\n"), 4,
                  {"vertex index -4 is out of range"});
  expectReadError(dir_.write("p.obj", "v 0 0 0\nf 1 2 3\n" + tri), 2,
                  {"vertex index 2 is out of range: 1 vertices"});  // no forward references
  expectReadError(dir_.write("q.obj", tri + "f 1 99999999999999999999999 3\n"), 4,
                  {"out of range"});
  expectReadError(dir_.write("r.obj", tri + "f 1 2\n"), 4,
                  {"face has 2 corners, expected at least 3"});
  expectReadError(dir_.write("s.obj", tri + "f\n"), 4, {"face has 0 corners"});
  expectReadError(dir_.write("t.obj", tri + "f 1 2 x\n"), 4,
                  {"corner 'x'", "expected an integer vertex index, found 'x'"});
  expectReadError(dir_.write("u.obj", tri + "f 1 2 3.0\n"), 4, {"found '3.0'"});
  expectReadError(dir_.write("v.obj", tri + "f 1/1/1/1 2 3\n"), 4,
                  {"corner '1/1/1/1'", "more than three"});
  expectReadError(dir_.write("w.obj", tri + "f 1/x 2 3\n"), 4,
                  {"non-zero integer texture index, found 'x'"});
  expectReadError(dir_.write("x.obj", tri + "f 1/ 2 3\n"), 4, {"texture index, found ''"});
  expectReadError(dir_.write("y.obj", tri + "f 1//0 2 3\n"), 4, {"normal index, found '0'"});
  expectReadError(dir_.write("z.obj", tri + "f 1/1/ 2 3\n"), 4, {"normal index, found ''"});
  expectReadError(dir_.write("aa.obj", tri + "f /1 2 3\n"), 4, {"found ''"});
  // A continued statement is reported at the line where it starts.
  expectReadError(dir_.write("ab.obj", tri + "\nf 1 \\\n 2 \\\n 7\nv 0 0 0\n"), 5,
                  {"vertex index 7"});
  // Binary data.
  expectReadError(dir_.write("ac.obj", tri + std::string("v 0 0 \0 0\n", 10)), 4, {"NUL byte"});
}

TEST_F(ObjIo, ReportsUnopenableFilesAndInvalidMeshes) {
  Mesh m;
  std::string error;
  const std::string missing = dir_.file("missing.obj");
  EXPECT_FALSE(readObj(missing, &m, &error));
  EXPECT_EQ(error.rfind(missing + ": cannot open for reading", 0), 0u) << error;
  EXPECT_FALSE(writeObj(dir_.file("no/such/dir/x.obj"), testMesh(false, 3), &error));
  EXPECT_NE(error.find("cannot open for writing"), std::string::npos) << error;
  Mesh bad = testMesh(true, 6);
  bad.colors.pop_back();
  EXPECT_FALSE(writeObj(dir_.file("bad.obj"), bad, &error));
  EXPECT_NE(error.find("cannot write OBJ"), std::string::npos) << error;
  EXPECT_NE(error.find("colours"), std::string::npos) << error;
  bad = testMesh(false, 6);
  bad.triangles.emplace_back(0, 1, 6);
  EXPECT_FALSE(writeObj(dir_.file("bad.obj"), bad, &error));
  EXPECT_NE(error.find("outside"), std::string::npos) << error;
}

// Random corruption must never crash (run under the sanitizers in CI).
TEST_F(ObjIo, SurvivesRandomCorruption) {
  const std::string p = dir_.file("c.obj");
  std::mt19937 rng(5);
  ASSERT_TRUE(writeObj(p, testMesh(true, 30), nullptr));
  const std::string full = test::readFile(p);
  const char alphabet[] = "v f/-+#\\\n 0123456789.e";
  for (int trial = 0; trial < 1000; ++trial) {
    std::string corrupt = full;
    std::uniform_int_distribution<size_t> pos(0, corrupt.size() - 1);
    for (int k = 0; k < 3; ++k) {
      corrupt[pos(rng)] =
          trial % 2 == 0 ? static_cast<char>(rng()) : alphabet[rng() % (sizeof(alphabet) - 1)];
    }
    if (trial % 3 == 0) corrupt.resize(pos(rng));
    dir_.write("c.obj", corrupt);
    Mesh m;
    std::string error;
    if (readObj(p, &m, &error)) {
      EXPECT_EQ(m.validate(), "");
    } else {
      EXPECT_EQ(error.rfind(p + ":", 0), 0u) << error;
    }
  }
}

}  // namespace
}  // namespace cblox
