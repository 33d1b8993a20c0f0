#include <cmath>
#include <fstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include "drivers/calibration/opencv_storage.h"
#include "test/test_support/temp_dir.h"

namespace cblox {
namespace {

void writeText(const std::string& path, const std::string& text) {
  std::ofstream(path, std::ios::binary) << text;
}

std::vector<std::string> strings(const YAML::Node& sequence) {
  std::vector<std::string> out;
  for (const YAML::Node& item : sequence) out.push_back(item.Scalar());
  return out;
}

OpenCvMatrix matrix(const YAML::Node& node) {
  OpenCvMatrix m;
  const std::string error = readOpenCvMatrix(node, &m);
  EXPECT_EQ(error, "");
  return m;
}

// What cv::FileStorage itself writes, in each of its three formats, reads back the same.
TEST(OpenCvStorageTest, ReadsWhatOpenCvWritesInEachFormat) {
  test::TempDir dir("cblox_opencv_storage");
  for (const std::string ext : {".yml", ".xml", ".json"}) {
    const std::string path = (dir.path() / ("written" + ext)).string();
    {
      cv::FileStorage fs(path, cv::FileStorage::WRITE);
      fs << "imagelist"
         << "["
         << "left01.jpg"
         << "a b.jpg"
         << "q\"u'o<t>&e"
         << "123"
         << "]";
      fs << "size" << std::vector<int>{640, 480};
      fs << "M" << (cv::Mat_<double>(2, 3) << 460, 0, 370.5, -0.1, 1e-300, 1);
      fs << "F" << (cv::Mat_<float>(1, 2) << 1.5f, -0.25f);
      fs << "I" << (cv::Mat_<int>(2, 1) << 7, -2);
      fs << "one" << (cv::Mat_<double>(1, 1) << 2.5);
      fs << "special" << (cv::Mat_<double>(1, 3) << NAN, INFINITY, -INFINITY);
      fs << "empty" << cv::Mat();
      fs << "name"
         << "hello world";
      fs << "nested"
         << "{"
         << "a" << 1 << "b"
         << "[" << 1 << 2 << "]"
         << "}";
      fs << "items"
         << "["
         << "{"
         << "x" << 1 << "}"
         << "{"
         << "x" << 2 << "}"
         << "]";
      fs << "rgb" << cv::Mat(1, 1, CV_8UC3, cv::Scalar(1, 2, 3));
    }
    std::string error;
    const std::optional<YAML::Node> root = readOpenCvStorage(path, &error);
    ASSERT_TRUE(root.has_value()) << ext << ": " << error;
    EXPECT_EQ(strings((*root)["imagelist"]),
              (std::vector<std::string>{"left01.jpg", "a b.jpg", "q\"u'o<t>&e", "123"}))
        << ext;
    EXPECT_EQ(strings((*root)["size"]), (std::vector<std::string>{"640", "480"})) << ext;
    const OpenCvMatrix m = matrix((*root)["M"]);
    EXPECT_EQ(m.rows, 2) << ext;
    EXPECT_EQ(m.cols, 3) << ext;
    EXPECT_EQ(m.values, (std::vector<double>{460, 0, 370.5, -0.1, 1e-300, 1})) << ext;
    EXPECT_EQ(matrix((*root)["F"]).values, (std::vector<double>{1.5, -0.25})) << ext;
    EXPECT_EQ(matrix((*root)["I"]).values, (std::vector<double>{7, -2})) << ext;
    EXPECT_EQ(matrix((*root)["one"]).values, std::vector<double>{2.5}) << ext;
    const OpenCvMatrix special = matrix((*root)["special"]);
    ASSERT_EQ(special.values.size(), 3u) << ext;
    EXPECT_TRUE(std::isnan(special.values[0])) << ext;
    EXPECT_EQ(special.values[1], INFINITY) << ext;
    EXPECT_EQ(special.values[2], -INFINITY) << ext;
    const OpenCvMatrix empty = matrix((*root)["empty"]);
    EXPECT_EQ(empty.rows, 0) << ext;
    EXPECT_TRUE(empty.values.empty()) << ext;
    EXPECT_EQ((*root)["name"].Scalar(), "hello world") << ext;
    EXPECT_EQ((*root)["nested"]["a"].Scalar(), "1") << ext;
    EXPECT_EQ(strings((*root)["nested"]["b"]), (std::vector<std::string>{"1", "2"})) << ext;
    ASSERT_TRUE((*root)["items"].IsSequence()) << ext;
    ASSERT_EQ((*root)["items"].size(), 2u) << ext;
    EXPECT_EQ((*root)["items"][1]["x"].Scalar(), "2") << ext;
    OpenCvMatrix rgb;
    EXPECT_EQ(readOpenCvMatrix((*root)["rgb"], &rgb),
              "dt '3u': expected one channel (u, c, w, s, i, f, d or h)")
        << ext;
    // The top-level keys keep the file's order (an image list is the first node).
    EXPECT_EQ(root->begin()->first.Scalar(), "imagelist") << ext;
  }
}

TEST(OpenCvStorageTest, XmlIsMappedOntoTheSameTree) {
  test::TempDir dir("cblox_opencv_storage");
  const std::string path = (dir.path() / "hand.xml").string();
  // No declaration, a comment, CDATA, a type_id, a sequence of maps, an empty element.
  writeText(path,
            "<opencv_storage><!-- hand written -->\n"
            "<K type_id=\"opencv-matrix\"><rows>1</rows><cols>2</cols><dt>d</dt>"
            "<data><![CDATA[1. 2.]]></data></K>\n"
            "<list><_><x>1</x></_><_>\"two words\"</_></list>\n"
            "<none></none>\n</opencv_storage>\n");
  std::string error;
  const std::optional<YAML::Node> root = readOpenCvStorage(path, &error);
  ASSERT_TRUE(root.has_value()) << error;
  EXPECT_EQ((*root)["K"]["type_id"].Scalar(), "opencv-matrix");
  EXPECT_EQ(matrix((*root)["K"]).values, (std::vector<double>{1, 2}));
  EXPECT_EQ((*root)["list"][0]["x"].Scalar(), "1");
  EXPECT_EQ((*root)["list"][1].Scalar(), "two words");
  EXPECT_TRUE((*root)["none"].IsNull());
}

TEST(OpenCvStorageTest, RefusesWhatItCannotReadWithTheReason) {
  test::TempDir dir("cblox_opencv_storage");
  struct Case {
    std::string text;
    std::string reason;
  };
  const Case cases[] = {
      {"<?xml version=\"1.0\"?>\n<opencv_storage>\n<a>1</a>\n", "not well-formed XML (line 4"},
      {"<?xml vsn=", "not well-formed XML (line 1"},  // B14's input
      {"<calibration><a>1</a></calibration>", "the root element is not <opencv_storage>"},
      {"<opencv_storage>\n<a>1<b>2</b></a></opencv_storage>", "line 2: <a>: both text"},
      {"<opencv_storage><a><_>1</_><b>2</b></a></opencv_storage>", "<b>: sequence items"},
      {"<opencv_storage>\n<a>1</a>\n<a>2</a></opencv_storage>", "line 3: <a>: given twice"},
      {"<opencv_storage><a>\"open ended</a></opencv_storage>", "unterminated quoted string"},
      {"<!DOCTYPE opencv_storage [<!ENTITY e \"x\">]><opencv_storage><a>&e;</a>"
       "</opencv_storage>",
       "unsupported XML content"},
      {"%YAML:1.\n -  d\n0a--\nimag40296y2%pYte: i'", "not well-formed YAML"},  // B15's input
      {"{\"a\": [1, 2}", "not well-formed JSON"},
      {"%YAML:1.0\n---\n- 1\n- 2\n", "the top level is not a map of named values"},
      {"", "the top level is not a map of named values"},
      {std::string("%YAML:1.0\na: [0\0]\n", 19), "NUL byte at offset 15"},
      {std::string((size_t{1} << 20) + 1, ' '), "too large"},
  };
  int i = 0;
  for (const Case& c : cases) {
    const std::string path = (dir.path() / ("case" + std::to_string(i++))).string();
    writeText(path, c.text);
    std::string error;
    EXPECT_FALSE(readOpenCvStorage(path, &error).has_value()) << c.text.substr(0, 80);
    EXPECT_EQ(error.rfind(path + ": ", 0), 0u) << error;
    EXPECT_NE(error.find(c.reason), std::string::npos) << c.text.substr(0, 80) << " -> " << error;
  }
  std::string error;
  EXPECT_FALSE(readOpenCvStorage((dir.path() / "absent").string(), &error).has_value());
  EXPECT_NE(error.find(": cannot open"), std::string::npos) << error;
  // A file of exactly the limit is read.
  const std::string limit = (dir.path() / "limit.yml").string();
  writeText(limit, "a: 1" + std::string((size_t{1} << 20) - 4, '\n'));
  EXPECT_TRUE(readOpenCvStorage(limit, &error).has_value()) << error;
}

TEST(OpenCvStorageTest, MatricesAreCheckedBeforeTheyAreRead) {
  struct Case {
    std::string yaml;
    std::string reason;
  };
  const Case cases[] = {
      {"[1, 2]", "not a matrix (expected rows, cols, dt and data)"},
      {"{rows: 1, cols: 1, data: [1]}", "not a matrix: dt is missing"},
      {"{rows: 1, cols: 2, dt: d, data: [1]}", "rows x cols is 2 but data holds 1 numbers"},
      {"{rows: 1, cols: 1, dt: d, data: [1, 2]}", "rows x cols is 1 but data holds 2 numbers"},
      {"{rows: 100000, cols: 100000, dt: d, data: [1]}", "rows x cols is 10000000000 but"},
      {"{rows: -1, cols: 1, dt: d, data: [1]}", "rows and cols must be integers >= 0"},
      {"{rows: 1.5, cols: 1, dt: d, data: [1]}", "rows and cols must be integers >= 0"},
      {"{rows: 1, cols: 1, dt: 2d, data: [1, 2]}", "dt '2d': expected one channel"},
      {"{rows: 1, cols: 1, dt: x, data: [1]}", "dt 'x': expected one channel"},
      {"{rows: 1, cols: 1, dt: d, data: [one]}", "data[0] is not a number"},
      {"{rows: 1, cols: 1, dt: d, data: {a: 1}}", "data is not a list"},
      {"{type_id: opencv-image, rows: 1, cols: 1, dt: d, data: [1]}", "type_id is not opencv"},
  };
  for (const Case& c : cases) {
    OpenCvMatrix m;
    m.rows = 9;
    EXPECT_EQ(readOpenCvMatrix(YAML::Load(c.yaml), &m).rfind(c.reason, 0), 0u) << c.yaml;
    EXPECT_EQ(m.rows, 9) << c.yaml;  // untouched on refusal
  }
  const OpenCvMatrix m = matrix(YAML::Load("{rows: 2, cols: 1, dt: 1f, data: [3, 4]}"));
  EXPECT_EQ(m.values, (std::vector<double>{3, 4}));
}

TEST(OpenCvStorageTest, NumbersAsOpenCvWritesThem) {
  EXPECT_EQ(parseOpenCvNumber("2."), 2.0);
  EXPECT_EQ(parseOpenCvNumber("-1.0000000000000001e-01"), -0.1);
  EXPECT_EQ(parseOpenCvNumber("+3"), 3.0);
  EXPECT_EQ(parseOpenCvNumber(".5"), 0.5);
  EXPECT_EQ(parseOpenCvNumber("-.5e1"), -5.0);
  EXPECT_TRUE(std::isnan(*parseOpenCvNumber(".Nan")));
  EXPECT_EQ(parseOpenCvNumber("-.INF"), -INFINITY);
  EXPECT_EQ(parseOpenCvNumber("+.inf"), INFINITY);
  for (const char* bad :
       {"", "-", "+", ".", "inf", "nan", "-inf", "1x", " 1", "1 ", "1e999", "0x10", "--1", "+-1"}) {
    EXPECT_FALSE(parseOpenCvNumber(bad).has_value()) << bad;
  }
}

}  // namespace
}  // namespace cblox
