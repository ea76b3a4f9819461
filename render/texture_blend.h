#pragma once
// The per-pixel blending of projective texturing (render/projective_texture.h): the input
// cameras in single precision, and the blended colour of one surface point. Internal to render/.

#include <cstdint>
#include <vector>

#include <Eigen/Core>

namespace confluent::render_internal {

// The most input cameras one frame may have.
constexpr int kMaxCameras = 32;

// One input camera as the blending (pass 2 of Render) sees it, in single precision.
struct BlendCamera {
  Eigen::Matrix3f rotation;
  Eigen::Vector3f translation, center, gain;
  float fx = 0, fy = 0, cx = 0, cy = 0, skew = 0;
  float k1 = 0, k2 = 0, p1 = 0, p2 = 0, k3 = 0;
  bool distorted = false;
  int width = 0, height = 0;              // image size
  const std::uint8_t* image = nullptr;    // RGB8, row-major
  float map_scale_x = 1, map_scale_y = 1; // depth-map pixels per image pixel
  int map_width = 0, map_height = 0;
  const float* depth_feather = nullptr;   // interleaved (camera z, feather), map_width x map_height
};

// What the blending needs besides the surface point: the view and the options.
struct BlendInput {
  Eigen::Vector3f view_center;
  float depth_bias = 0, resolution_weight = 0, grazing_cos = 0;
  int best_k = 1;
};

// The blended RGB8 colour of surface point X (world) with unit normal n (towards the view) into
// out[0..2] (see the header for the weighting); false, and out untouched, when no camera sees X.
// The cheap tests come first, so that cameras facing away cost little.
bool BlendPixel(const BlendInput& in, const std::vector<BlendCamera>& cameras, const Eigen::Vector3f& X,
                const Eigen::Vector3f& n, std::uint8_t* out);

}  // namespace confluent::render_internal
