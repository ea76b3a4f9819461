#pragma once
// Synthetic checkerboard images with known cameras, for tests, demos and the studio.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <vector>

#include "calib/camera.h"
#include "calib/checkerboard.h"
#include "core/image.h"

namespace confluent {

// Options of RenderCheckerboard.
struct SyntheticBoardOptions {
  int supersampling = 4;         // samples per pixel side on pixels crossed by a square edge
  double noise_sigma = 1.0;      // Gaussian noise, grey levels (0-255)
  std::uint32_t seed = 1;        // noise seed
  double dark = 30.0;            // grey level of dark squares
  double light = 220.0;          // grey level of light squares and of the white border
  double background = 100.0;     // grey level where no board is seen
  double back_side = 140.0;      // grey level of the board's (blank) back
  double border_squares = 1.0;   // white margin around the pattern, in squares

  // Throws UsageError on a non-positive supersampling, negative noise or margin.
  void Check() const;
};

// Renders a single-channel 8-bit image of `board` posed at `world_from_board` (board frame as
// in checkerboard.h: corner 0 at the origin, pattern in z = 0, front face towards -z) as seen
// by `camera`, distortion included. Every pixel is mapped back to the board plane (undistort,
// ray, plane intersection); pixels crossed by a square edge are supersampled, so corners are
// exact to a small fraction of a pixel. The square outside corner 0 is dark.
Image RenderCheckerboard(const Camera& camera, const CheckerboardSpec& board,
                         const Eigen::Isometry3d& world_from_board, const SyntheticBoardOptions& options = {});

// Renders many poses of one board for one camera; the per-pixel undistortion is computed once.
class CheckerboardRenderer {
 public:
  CheckerboardRenderer(const Camera& camera, const CheckerboardSpec& board, const SyntheticBoardOptions& options = {});
  // As RenderCheckerboard, with the noise seeded by `seed`.
  Image Render(const Eigen::Isometry3d& world_from_board, std::uint32_t seed) const;

 private:
  Camera camera_;
  CheckerboardSpec board_;
  SyntheticBoardOptions options_;
  std::vector<Eigen::Vector2d> lattice_;  // normalized undistorted coords of pixel corners
};

// Exact distorted projections of the inner corners, in checkerboard.h order.
std::vector<Eigen::Vector2d> ProjectCheckerboard(const Camera& camera, const CheckerboardSpec& board,
                                                 const Eigen::Isometry3d& world_from_board);

// True when the camera sees the board's front, every inner corner projects at least
// `margin_px` inside the image, and the board plane is viewed at most `max_obliquity_deg`
// from its normal.
bool CheckerboardVisible(const Camera& camera, const CheckerboardSpec& board,
                         const Eigen::Isometry3d& world_from_board, double margin_px,
                         double max_obliquity_deg = 70.0);

// A ring of `count` cameras at `radius_m` from the z axis and `height_m` above z = 0, evenly
// spaced, each looking at `target_in_world`, upright (image y down = world -z), named
// "cam00", "cam01", ..., with the given image size, focal length and distortion.
Rig MakeRingRig(int count, double radius_m, double height_m, const Eigen::Vector3d& target_in_world,
                int width, int height, double focal_px, const Vector5d& dist = Vector5d::Zero());

// `count` random, reproducible board poses (world_from_board) for a ring of cameras around the
// z axis: board centre uniformly in a cylinder (radius `radius_m`, z from `min_z_m` to
// `max_z_m`), board upright facing a random horizontal direction, tilted up to `max_tilt_deg`
// about its x and y axes and turned up to `max_roll_deg` in its plane.
std::vector<Eigen::Isometry3d> MakeBoardPoses(int count, const CheckerboardSpec& board, double radius_m,
                                              double min_z_m, double max_z_m, double max_tilt_deg,
                                              double max_roll_deg, std::uint32_t seed);

}  // namespace confluent
