// INTERNAL to export/uv_atlas.cc: a flattened chart of the UV atlas, its orientation to its
// principal axes and the skyline packing of the charts into the square atlas.
#pragma once

#include <Eigen/Core>
#include <vector>

namespace confluent::uv_atlas_internal {

// One chart: its faces, its vertices' flattened coordinates and its place in the atlas.
struct Chart {
  std::vector<int> faces;
  std::vector<int> vertices;           // mesh vertex of each chart vertex
  std::vector<Eigen::Vector2d> uv;     // per chart vertex, metres (area-normalised)
  std::vector<int> local;              // per face corner (3 per face): chart vertex
  double min_u = 0, min_v = 0, width = 0, height = 0;
  int x = 0, y = 0;                    // packed position (texels, lower-left of the box)
  bool turned = false;                 // packed turned by 90 degrees
};

// Rotates a chart to its principal axes, long side along u, and records its bounding box.
void OrientChart(Chart* chart);

// Skyline bottom-left packing at `texels_per_m` (Jylanki 2010, "A Thousand Ways to Pack the
// Bin"): charts in `order` (tallest first), each at the position, upright or turned by 90
// degrees, where its top is lowest, inside `padding` texels of gutter; false when they do not
// fit a `size` x `size` atlas.
bool Pack(std::vector<Chart>* charts, const std::vector<int>& order, double texels_per_m, int size, int padding);

}  // namespace confluent::uv_atlas_internal
