#include "core/geometry/image.h"

#include <sstream>
#include <stdexcept>

#include <gtest/gtest.h>

#include "core/geometry/color.h"

namespace cblox {
namespace {

TEST(Image, DefaultIsEmpty) {
  const DepthImage image;
  EXPECT_TRUE(image.empty());
  EXPECT_EQ(image.width, 0);
  EXPECT_EQ(image.height, 0);
}

TEST(Image, FillAndRowMajorLayout) {
  DepthImage image(4, 3, 1.5f);
  EXPECT_FALSE(image.empty());
  ASSERT_EQ(image.data.size(), 12u);
  for (float d : image.data) EXPECT_EQ(d, 1.5f);
  image(3, 1) = 7.0f;  // u = 3 (column), v = 1 (row)
  EXPECT_EQ(image.data[1 * 4 + 3], 7.0f);
  const DepthImage& cref = image;
  EXPECT_EQ(cref(3, 1), 7.0f);
}

TEST(Image, ContainsAndSameSize) {
  const ColorImage image(4, 3);
  EXPECT_TRUE(image.contains(0, 0));
  EXPECT_TRUE(image.contains(3, 2));
  EXPECT_FALSE(image.contains(4, 0));
  EXPECT_FALSE(image.contains(0, 3));
  EXPECT_FALSE(image.contains(-1, 0));
  EXPECT_TRUE(image.sameSize(DepthImage(4, 3)));
  EXPECT_FALSE(image.sameSize(DepthImage(3, 4)));
}

TEST(Image, NegativeSizeThrows) { EXPECT_THROW(DepthImage(-1, 3), std::invalid_argument); }

TEST(Image, ZeroSizeIsEmpty) { EXPECT_TRUE(DepthImage(0, 5).empty()); }

TEST(Color, DefaultsAndEquality) {
  const Color black;
  EXPECT_EQ(black, (Color{0, 0, 0}));
  const Color c{10, 20, 30};
  EXPECT_EQ(c, (Color{10, 20, 30}));
  EXPECT_FALSE(c == (Color{10, 20, 31}));
  const ColorImage image(2, 2, c);
  EXPECT_EQ(image(1, 1), c);
  std::ostringstream os;
  os << c;
  EXPECT_EQ(os.str(), "(10, 20, 30)");
}

}  // namespace
}  // namespace cblox
