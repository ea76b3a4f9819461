#include "render/composite.h"

#include <gtest/gtest.h>

#include <string>

#include "core/error.h"

namespace confluent {
namespace {

// A W x H render whose silhouette covers the columns x < edge, in a flat colour.
RenderResult HalfCovered(int width, int height, int edge, std::uint8_t r, std::uint8_t g, std::uint8_t b) {
  RenderResult rendered;
  rendered.color = Image(width, height, 3);
  rendered.silhouette = Image(width, height, 1);
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < edge; ++x) {
      const std::size_t p = static_cast<std::size_t>(y) * width + x;
      rendered.silhouette.data[p] = 255;
      rendered.color.data[3 * p] = r, rendered.color.data[3 * p + 1] = g, rendered.color.data[3 * p + 2] = b;
    }
  return rendered;
}

Image Flat(int width, int height, std::uint8_t v) {
  Image image(width, height, 3);
  std::fill(image.data.begin(), image.data.end(), v);
  return image;
}

TEST(CompositeOverBackground, RenderedPixelsOverThePlateElsewhere) {
  RenderResult rendered;
  rendered.color = Image(3, 2, 3);
  rendered.silhouette = Image(3, 2, 1);
  Image plate(3, 2, 3);
  for (std::size_t i = 0; i < rendered.color.data.size(); ++i) {
    rendered.color.data[i] = static_cast<std::uint8_t>(200 + i);
    plate.data[i] = static_cast<std::uint8_t>(10 + i);
  }
  rendered.silhouette.data = {255, 0, 0, 0, 255, 0};
  const Image out = CompositeOverBackground(rendered, plate, "plate.png");
  for (std::size_t p = 0; p < 6; ++p)
    for (int c = 0; c < 3; ++c)
      EXPECT_EQ(out.data[3 * p + c], (rendered.silhouette.data[p] ? rendered.color : plate).data[3 * p + c]) << p;
}

// Matting: across a straight outline the colour ramps from the render's to the plate's, with the
// mid value at the outline; far from it both sides are untouched.
TEST(CompositeOverBackground, SoftEdgeRampsAcrossTheOutline) {
  const int width = 20, height = 5, edge = 10;
  const RenderResult rendered = HalfCovered(width, height, edge, 200, 100, 50);
  const Image plate = Flat(width, height, 0);
  const Image out = CompositeOverBackground(rendered, plate, "plate.png", 0.5);
  auto red = [&](int x) { return static_cast<int>(out.data[3 * (2 * width + x)]); };
  EXPECT_EQ(red(0), 200);
  EXPECT_EQ(red(width - 1), 0);
  EXPECT_EQ(out.data[3 * (2 * width + 2) + 1], 100);
  for (int x = 1; x < width; ++x) EXPECT_LE(red(x), red(x - 1)) << x;  // monotone
  EXPECT_GT(red(edge - 1), 100);  // the last covered pixel: mostly the render
  EXPECT_LT(red(edge - 1), 200);
  EXPECT_GT(red(edge), 0);  // the first uncovered one: some of the render's colour
  EXPECT_LT(red(edge), 100);
  EXPECT_NEAR(red(edge - 1) + red(edge), 200, 2);  // symmetric about the outline
  // Outside the silhouette the colour mixed in is the render's nearby colour, not black.
  const Image grey = CompositeOverBackground(rendered, Flat(width, height, 255), "plate.png", 0.5);
  EXPECT_GT(grey.data[3 * (2 * width + edge) + 2], 50);
  EXPECT_LT(grey.data[3 * (2 * width + edge) + 2], 255);
  // Softness 0 is the binary composite.
  const Image hard = CompositeOverBackground(rendered, plate, "plate.png", 0.0);
  EXPECT_EQ(hard.data[3 * (2 * width + edge - 1)], 200);
  EXPECT_EQ(hard.data[3 * (2 * width + edge)], 0);
}

TEST(CompositeOverBackground, MismatchedPlateIsAnInputErrorNamingIt) {
  RenderResult rendered;
  rendered.color = Image(4, 4, 3);
  rendered.silhouette = Image(4, 4, 1);
  try {
    CompositeOverBackground(rendered, Image(5, 4, 3), "background/cam03.png");
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("background/cam03.png"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("5x4"), std::string::npos) << e.what();
  }
  RenderResult no_silhouette;
  no_silhouette.color = Image(4, 4, 3);
  EXPECT_THROW(CompositeOverBackground(no_silhouette, Image(4, 4, 3), "p.png"), InputError);
  EXPECT_THROW(CompositeOverBackground(rendered, Image(4, 4, 3), "p.png", -1.0), UsageError);
}

}  // namespace
}  // namespace confluent
