#include "core/io/ply_io.h"

#include <cstdint>
#include <cstring>
#include <limits>
#include <random>
#include <string>

#include <gtest/gtest.h>

#include "test/test_support/awkward_mesh.h"
#include "test/test_support/temp_dir.h"

namespace cblox {
namespace {

class PlyIo : public ::testing::Test {
 protected:
  // Expects readPly to fail with a message containing the file name and every fragment.
  void expectReadError(const std::string& p, std::initializer_list<const char*> fragments) {
    Mesh mesh;
    std::string error;
    EXPECT_FALSE(readPly(p, &mesh, &error)) << p;
    EXPECT_NE(error.find(p), std::string::npos) << error;
    for (const char* f : fragments) EXPECT_NE(error.find(f), std::string::npos) << error;
    std::printf("  rejected: %s\n", error.c_str());
  }

  test::TempDir dir_{"cblox_ply"};
};

// Awkward floats on purpose (see awkwardMesh), the same on every run.
Mesh testMesh(bool colors, bool normals, size_t num_vertices = 200) {
  return test::awkwardMesh(7, colors, normals, num_vertices);
}

TEST_F(PlyIo, RoundTripBinaryAndAsciiIsExact) {
  for (const bool colors : {false, true}) {
    for (const bool normals : {false, true}) {
      const Mesh mesh = testMesh(colors, normals);
      for (const PlyFormat format : {PlyFormat::kBinaryLittleEndian, PlyFormat::kAscii}) {
        const std::string p = dir_.file("mesh.ply");
        std::string error;
        ASSERT_TRUE(writePly(p, mesh, format, &error)) << error;
        Mesh back;
        ASSERT_TRUE(readPly(p, &back, &error)) << error;
        SCOPED_TRACE(std::string(format == PlyFormat::kAscii ? "ascii" : "binary") +
                     (colors ? " colours" : "") + (normals ? " normals" : ""));
        test::expectSameMesh(mesh, back);
      }
    }
  }
}

TEST_F(PlyIo, HeaderIsWhatMeshLabAndOpen3dExpect) {
  const Mesh mesh = testMesh(true, true, 10);
  const std::string p = dir_.file("h.ply");
  ASSERT_TRUE(writePly(p, mesh, PlyFormat::kBinaryLittleEndian, nullptr));
  const std::string content = test::readFile(p);
  const std::string header = content.substr(0, content.find("end_header\n") + 11);
  EXPECT_EQ(header,
            "ply\nformat binary_little_endian 1.0\ncomment written by cblox\n"
            "element vertex 10\nproperty float x\nproperty float y\nproperty float z\n"
            "property float nx\nproperty float ny\nproperty float nz\n"
            "property uchar red\nproperty uchar green\nproperty uchar blue\n"
            "element face 5\nproperty list uchar int vertex_indices\nend_header\n");
  // 10 vertices * (6 floats + 3 bytes) + 5 faces * (1 + 3 ints).
  EXPECT_EQ(content.size(), header.size() + 10 * 27 + 5 * 13);
}

TEST_F(PlyIo, PointCloudWritesEmptyFaceElement) {
  Mesh cloud = testMesh(true, false, 5);
  cloud.triangles.clear();
  for (const PlyFormat format : {PlyFormat::kBinaryLittleEndian, PlyFormat::kAscii}) {
    const std::string p = dir_.file("cloud.ply");
    ASSERT_TRUE(writePly(p, cloud, format, nullptr));
    EXPECT_NE(test::readFile(p).find("element face 0\n"), std::string::npos);
    Mesh back;
    std::string error;
    ASSERT_TRUE(readPly(p, &back, &error)) << error;
    test::expectSameMesh(cloud, back);
  }
  // Even an empty mesh is a valid file.
  const std::string p = dir_.file("empty.ply");
  ASSERT_TRUE(writePly(p, Mesh{}, PlyFormat::kAscii, nullptr));
  Mesh back = testMesh(false, false, 4);
  ASSERT_TRUE(readPly(p, &back, nullptr));
  EXPECT_TRUE(back.empty());
}

TEST_F(PlyIo, ReadsForeignAsciiWithArbitraryPropertiesAndPolygons) {
  const std::string p = dir_.write("foreign.ply",
                                   "ply\r\n"
                                   "format ascii 1.0\r\n"
                                   "comment from some other tool\r\n"
                                   "obj_info whatever\r\n"
                                   "element vertex 5\r\n"
                                   "property double z\r\n"
                                   "property float quality\r\n"
                                   "property double x\r\n"
                                   "property int y\r\n"
                                   "property list uchar float texcoord\r\n"
                                   "property uchar red\r\n"
                                   "property uchar green\r\n"
                                   "property uchar blue\r\n"
                                   "property uchar alpha\r\n"
                                   "element material 1\r\n"
                                   "property float shininess\r\n"
                                   "element face 2\r\n"
                                   "property list int uint vertex_index\r\n"
                                   "property uchar flags\r\n"
                                   "end_header\r\n"
                                   "3 0.5 1 2 2 0.1 0.2 255 0 10 255\r\n"
                                   "4 0.5 1.5 3 0 10 20 30 40\r\n"
                                   "\r\n"
                                   "5 0.5 -1 -4 1 7 +1 2 3 4\r\n"
                                   "6 0.5 1e1 5 0 1 1 1 0\r\n"
                                   "7 0.5 2.5E-1 6 0 0 0 0 0\r\n"
                                   "0.9\r\n"
                                   "4 0 1 2 3 7\r\n"
                                   "3 4 3 2 0\r\n");
  Mesh m;
  std::string error;
  ASSERT_TRUE(readPly(p, &m, &error)) << error;
  ASSERT_EQ(m.numVertices(), 5u);
  EXPECT_EQ(m.vertices[0], Eigen::Vector3f(1.0f, 2.0f, 3.0f));
  EXPECT_EQ(m.vertices[2], Eigen::Vector3f(-1.0f, -4.0f, 5.0f));
  EXPECT_EQ(m.vertices[3], Eigen::Vector3f(10.0f, 5.0f, 6.0f));
  EXPECT_EQ(m.vertices[4], Eigen::Vector3f(0.25f, 6.0f, 7.0f));
  EXPECT_EQ(m.colors[0], (Color{255, 0, 10}));
  EXPECT_EQ(m.colors[2], (Color{1, 2, 3}));
  EXPECT_TRUE(m.normals.empty());
  // The quad becomes a fan of two triangles.
  ASSERT_EQ(m.numTriangles(), 3u);
  EXPECT_EQ(m.triangles[0], Eigen::Vector3i(0, 1, 2));
  EXPECT_EQ(m.triangles[1], Eigen::Vector3i(0, 2, 3));
  EXPECT_EQ(m.triangles[2], Eigen::Vector3i(4, 3, 2));
}

// Builds a binary little-endian body by hand.
class Bytes {
 public:
  template <typename T>
  Bytes& put(T v) {
    char b[sizeof(T)];
    std::memcpy(b, &v, sizeof(T));
    if constexpr (std::endian::native == std::endian::big) std::reverse(b, b + sizeof(T));
    data_.append(b, sizeof(T));
    return *this;
  }
  const std::string& str() const { return data_; }

 private:
  std::string data_;
};

TEST_F(PlyIo, ReadsForeignBinaryWithMixedTypes) {
  Bytes body;
  // vertex: double x, double y, double z, short skip, float nx, float ny, float nz,
  //         float red green blue (0..1)
  for (int i = 0; i < 4; ++i) {
    body.put<double>(i).put<double>(2.0 * i).put<double>(-0.5 * i).put<int16_t>(-7);
    body.put<float>(0).put<float>(0).put<float>(1);
    body.put<float>(1.0f).put<float>(0.5f).put<float>(-3.0f);
  }
  // face: ushort count, int indices; an extra list of uchar; a triangle and a quad.
  body.put<uint16_t>(3).put<int32_t>(0).put<int32_t>(1).put<int32_t>(2);
  body.put<uint8_t>(1).put<uint8_t>(9);
  body.put<uint16_t>(4).put<int32_t>(0).put<int32_t>(1).put<int32_t>(2).put<int32_t>(3);
  body.put<uint8_t>(0);
  const std::string p = dir_.write(
      "binary.ply",
      "ply\nformat binary_little_endian 1.0\nelement vertex 4\n"
      "property float64 x\nproperty float64 y\nproperty float64 z\nproperty short s\n"
      "property float nx\nproperty float ny\nproperty float nz\n"
      "property float red\nproperty float green\nproperty float blue\n"
      "element face 2\nproperty list ushort int vertex_indices\nproperty list uchar uchar extra\n"
      "end_header\n" +
          body.str());
  Mesh m;
  std::string error;
  ASSERT_TRUE(readPly(p, &m, &error)) << error;
  ASSERT_EQ(m.numVertices(), 4u);
  EXPECT_EQ(m.vertices[3], Eigen::Vector3f(3.0f, 6.0f, -1.5f));
  ASSERT_EQ(m.normals.size(), 4u);
  EXPECT_EQ(m.normals[2], Eigen::Vector3f(0, 0, 1));
  EXPECT_EQ(m.colors[1], (Color{255, 128, 0}));
  ASSERT_EQ(m.numTriangles(), 3u);
  EXPECT_EQ(m.triangles[2], Eigen::Vector3i(0, 2, 3));
}

TEST_F(PlyIo, ReadsBigEndian) {
  std::string body;
  const auto be_float = [&body](float v) {
    char b[4];
    std::memcpy(b, &v, 4);
    if constexpr (std::endian::native == std::endian::little) std::reverse(b, b + 4);
    body.append(b, 4);
  };
  for (float v : {1.5f, -2.0f, 3.25f}) be_float(v);
  const std::string p =
      dir_.write("be.ply",
                 "ply\nformat binary_big_endian 1.0\nelement vertex 1\nproperty float x\n"
                 "property float y\nproperty float z\nend_header\n" +
                     body);
  Mesh m;
  std::string error;
  ASSERT_TRUE(readPly(p, &m, &error)) << error;
  ASSERT_EQ(m.numVertices(), 1u);
  EXPECT_EQ(m.vertices[0], Eigen::Vector3f(1.5f, -2.0f, 3.25f));
}

TEST_F(PlyIo, RejectsTruncatedBinary) {
  const std::string p = dir_.file("t.ply");
  ASSERT_TRUE(writePly(p, testMesh(true, true, 50), PlyFormat::kBinaryLittleEndian, nullptr));
  const std::string full = test::readFile(p);
  // Cut inside the face data, inside the vertex data, and right after the header.
  for (const size_t cut :
       {full.size() - 5, full.size() - 25 * 13 - 100, full.find("end_header\n") + 11}) {
    dir_.write("t.ply", full.substr(0, cut));
    expectReadError(p, {"truncated"});
  }
}

TEST_F(PlyIo, RejectsTruncatedAscii) {
  const std::string p = dir_.file("t.ply");
  ASSERT_TRUE(writePly(p, testMesh(false, false, 20), PlyFormat::kAscii, nullptr));
  const std::string full = test::readFile(p);
  dir_.write("t.ply", full.substr(0, full.size() - 12));  // last face line loses values
  expectReadError(p, {"element 'face'", "line"});
  dir_.write("t.ply", full.substr(0, full.find("end_header\n") + 11 + 30));
  expectReadError(p, {"element 'vertex'", "line"});
}

TEST_F(PlyIo, RejectsBadHeaders) {
  const std::string vertex =
      "element vertex 1\nproperty float x\nproperty float y\nproperty float z\n";
  expectReadError(dir_.write("a.ply", ""), {"empty"});
  expectReadError(dir_.write("b.ply", "PLY\nformat ascii 1.0\nend_header\n"), {"not a PLY file"});
  expectReadError(dir_.write("c.ply", "ply\nformat ascii 2.0\n" + vertex + "end_header\n0 0 0\n"),
                  {"header line 2", "version"});
  expectReadError(dir_.write("d.ply", "ply\nformat fancy 1.0\n" + vertex + "end_header\n"),
                  {"header line 2", "unknown format 'fancy'"});
  expectReadError(dir_.write("e.ply", "ply\nformat ascii 1.0\n" + vertex), {"end_header"});
  expectReadError(dir_.write("f.ply", "ply\nformat ascii 1.0\nelement vertex -3\nend_header\n"),
                  {"header line 3", "count"});
  expectReadError(
      dir_.write("g.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty quad x\nend_header\n"),
      {"header line 4", "unknown property type 'quad'"});
  expectReadError(dir_.write("h.ply", "ply\nformat ascii 1.0\nproperty float x\nend_header\n"),
                  {"header line 3", "before any 'element'"});
  expectReadError(dir_.write("i.ply", "ply\n" + vertex + "end_header\n0 0 0\n"), {"'format'"});
  expectReadError(dir_.write("j.ply", "ply\nformat ascii 1.0\nfrobnicate\nend_header\n"),
                  {"header line 3", "unknown keyword 'frobnicate'"});
  expectReadError(dir_.write("k.ply",
                             "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n"
                             "end_header\n0\n"),
                  {"x, y, z"});
  expectReadError(dir_.write("l.ply",
                             "ply\nformat ascii 1.0\nelement face 0\n"
                             "property list uchar int vertex_indices\nend_header\n"),
                  {"no 'vertex' element"});
  expectReadError(
      dir_.write("m.ply", "ply\nformat ascii 1.0\n" + vertex +
                              "element face 1\nproperty uchar n\nend_header\n0 0 0\n1\n"),
      {"vertex_indices"});
  // A header count far beyond the file size is caught before any allocation.
  expectReadError(dir_.write("n.ply",
                             "ply\nformat binary_little_endian 1.0\n"
                             "element vertex 99999999999999\nproperty float x\n"
                             "property float y\nproperty float z\nend_header\n"),
                  {"truncated"});
}

TEST_F(PlyIo, RejectsBadFacesAndValues) {
  const std::string head =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
      "property float z\nproperty uchar red\nproperty uchar green\nproperty uchar blue\n"
      "element face 1\nproperty list uchar int vertex_indices\nend_header\n";
  const std::string verts = "0 0 0 1 2 3\n1 0 0 1 2 3\n0 1 0 1 2 3\n";
  expectReadError(dir_.write("a.ply", head + verts + "3 0 1 3\n"),
                  {"line 16", "element 'face' #0", "vertex index 3 is out of range [0, 3)"});
  expectReadError(dir_.write("b.ply", head + verts + "3 0 -1 2\n"), {"out of range"});
  expectReadError(dir_.write("c.ply", head + verts + "2 0 1\n"), {"at least 3"});
  expectReadError(dir_.write("d.ply", head + verts + "3 0 1 2 7\n"), {"line 16", "found 5"});
  expectReadError(dir_.write("e.ply", head + "0 0 zero 1 2 3\n"),
                  {"line 13", "element 'vertex' #0", "property 'z'", "'zero'"});
  expectReadError(dir_.write("f.ply", head + "0 0 0 1 2 300\n"), {"does not fit type uchar"});
  expectReadError(dir_.write("g.ply", head + "0 0 0 1 2 3.5\n"), {"expected an integer"});

  // Binary: out-of-range index.
  Bytes body;
  for (int i = 0; i < 3; ++i) body.put<float>(0).put<float>(0).put<float>(0);
  body.put<uint8_t>(3).put<int32_t>(0).put<int32_t>(1).put<int32_t>(1000);
  expectReadError(dir_.write("h.ply",
                             "ply\nformat binary_little_endian 1.0\nelement vertex 3\n"
                             "property float x\nproperty float y\nproperty float z\n"
                             "element face 1\nproperty list uchar int vertex_indices\n"
                             "end_header\n" +
                                 body.str()),
                  {"element 'face' #0", "vertex index 1000 is out of range [0, 3)"});
}

TEST_F(PlyIo, ReportsUnopenableFilesAndInvalidMeshes) {
  Mesh m;
  std::string error;
  EXPECT_FALSE(readPly(dir_.file("missing.ply"), &m, &error));
  EXPECT_NE(error.find("cannot open"), std::string::npos) << error;
  EXPECT_FALSE(writePly(dir_.file("no/such/dir/x.ply"), testMesh(false, false, 3),
                        PlyFormat::kAscii, &error));
  EXPECT_NE(error.find("cannot open"), std::string::npos) << error;
  Mesh bad = testMesh(true, false, 6);
  bad.colors.pop_back();
  EXPECT_FALSE(writePly(dir_.file("bad.ply"), bad, PlyFormat::kBinaryLittleEndian, &error));
  EXPECT_NE(error.find("colours"), std::string::npos) << error;
  bad = testMesh(false, false, 6);
  bad.triangles.emplace_back(0, 1, 6);
  EXPECT_FALSE(writePly(dir_.file("bad.ply"), bad, PlyFormat::kAscii, &error));
  EXPECT_NE(error.find("outside"), std::string::npos) << error;
}

// Random corruption must never crash (run under the sanitizers in CI).
TEST_F(PlyIo, SurvivesRandomCorruption) {
  const std::string p = dir_.file("c.ply");
  std::mt19937 rng(3);
  for (const PlyFormat format : {PlyFormat::kBinaryLittleEndian, PlyFormat::kAscii}) {
    ASSERT_TRUE(writePly(p, testMesh(true, true, 30), format, nullptr));
    const std::string full = test::readFile(p);
    for (int trial = 0; trial < 300; ++trial) {
      std::string corrupt = full;
      std::uniform_int_distribution<size_t> pos(0, corrupt.size() - 1);
      for (int k = 0; k < 3; ++k) corrupt[pos(rng)] = static_cast<char>(rng());
      if (trial % 3 == 0) corrupt.resize(pos(rng));
      dir_.write("c.ply", corrupt);
      Mesh m;
      std::string error;
      if (readPly(p, &m, &error)) {
        EXPECT_EQ(m.validate(), "");
      } else {
        EXPECT_FALSE(error.empty());
      }
    }
  }
}

}  // namespace
}  // namespace cblox
