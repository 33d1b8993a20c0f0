#include "core/eval/json_writer.h"

#include <limits>
#include <string>

#include <gtest/gtest.h>

namespace cblox {
namespace {

TEST(JsonWriterTest, NumbersAreShortestAndNonFiniteIsNull) {
  EXPECT_EQ(jsonNumber(0.0), "0");
  EXPECT_EQ(jsonNumber(0.05), "0.05");
  EXPECT_EQ(jsonNumber(-2.5), "-2.5");
  EXPECT_EQ(std::stod(jsonNumber(0.1 + 0.2)), 0.1 + 0.2);
  EXPECT_EQ(jsonNumber(std::numeric_limits<double>::infinity()), "null");
  EXPECT_EQ(jsonNumber(std::numeric_limits<double>::quiet_NaN()), "null");
  EXPECT_EQ(jsonArray({1.0, 0.5, std::numeric_limits<double>::infinity()}), "[1, 0.5, null]");
  EXPECT_EQ(jsonArray({}), "[]");
}

TEST(JsonWriterTest, StringsAreEscaped) {
  EXPECT_EQ(jsonQuoted("plain/path.ply"), "\"plain/path.ply\"");
  EXPECT_EQ(jsonQuoted("a\"b\\c"), "\"a\\\"b\\\\c\"");
  EXPECT_EQ(jsonQuoted("l1\nl2\t\r"), "\"l1\\nl2\\t\\r\"");
  EXPECT_EQ(jsonQuoted(std::string("\x01", 1)), "\"\\u0001\"");
  EXPECT_EQ(jsonQuoted("m\xc3\xa4h"), "\"m\xc3\xa4h\"");  // UTF-8 kept
}

TEST(JsonWriterTest, ObjectsNestWithTwoSpaceIndentation) {
  JsonObject inner("  ");
  inner.num("x", 1.5);
  inner.boolean("ok", true);
  JsonObject root("");
  root.count("n", 3);
  root.str("name", "a");
  root.raw("inner", inner.close());
  root.raw("empty", JsonObject("  ").close());
  EXPECT_EQ(root.close(),
            "{\n  \"n\": 3,\n  \"name\": \"a\",\n  \"inner\": {\n    \"x\": 1.5,\n    \"ok\": "
            "true\n  },\n  \"empty\": {}\n}");
  // A top-level object nested one level down.
  EXPECT_EQ(jsonNest("{\n  \"a\": 1\n}\n", "  "), "{\n    \"a\": 1\n  }");
}

}  // namespace
}  // namespace cblox
