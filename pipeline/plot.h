#pragma once
// Small charts and heat maps drawn into images, for reports (metrics per frame, error maps).

#include <array>
#include <string>
#include <vector>

#include "core/image.h"

namespace confluent {

// One line of a chart: y values at the given x values (same length).
struct PlotSeries {
  std::string label;
  std::vector<double> x;
  std::vector<double> y;
  unsigned char r = 0, g = 0, b = 0;  // line colour
};

// A line chart (RGB8, width x height) with axes, ticks, a title and a legend. The y range is
// fitted to the data (padded by 5%) unless y_min < y_max.
Image DrawLineChart(const std::vector<PlotSeries>& series, const std::string& title, const std::string& x_label,
                    const std::string& y_label, int width = 900, int height = 420, double y_min = 0.0,
                    double y_max = 0.0);

// A 1-channel float image in [0, max_value] as a colour-mapped RGB8 heat map (turbo colour
// map) with a colour bar labelled from 0 to max_value.
Image DrawHeatMap(const Image& values, double max_value, const std::string& title);

// The bounding box {x, y, width, height} of the non-zero pixels of a 1-channel mask, grown by
// `margin` times its size on each side and clipped to the image; the whole image when empty.
std::array<int, 4> MaskBox(const Image& mask, double margin);

// The part {x, y, width, height} of an image (the box must lie inside it).
Image CropImage(const Image& image, const std::array<int, 4>& box);

// Images placed side by side (same height; RGB8), each with a caption strip above it.
Image SideBySide(const std::vector<Image>& images, const std::vector<std::string>& captions);

}  // namespace confluent
