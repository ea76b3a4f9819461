#pragma once
// Checkerboard calibration targets: description, board points, and corner detection.
//
// Corner order. Corners are indexed row-major: index = row * cols + col, where the board frame
// has x along a row (col increases), y along a column (row increases), z = x cross y, and the
// board lies in z = 0 with corner 0 at the origin. A printed board is seen from its front, and
// then its z axis points away from the camera; DetectCheckerboard always returns that
// handedness (a mirrored order is reversed row by row).
//
// The 180-degree ambiguity. When cols + rows is even (e.g. 8x6), the pattern looks the same
// after a half turn in its plane, so an image alone cannot tell corner 0 from the last one.
// DetectCheckerboard applies a fixed image rule (corner 0 is the end of the diagonal with the
// smaller x + y, i.e. nearer the top-left of the image), which is consistent between upright
// cameras looking at the same side of the board. Multi-camera calibration does not rely on it:
// CalibrateRig (calib/calibrate.h) re-decides each view's half turn from the consensus of all
// cameras that see the frame. When cols + rows is odd the opposite corner squares have
// different colours, and the detector uses that to make the order unique: the square
// diagonally outside corner 0 is the dark one (board square (i, j), i = floor(x / square) + 1,
// j = floor(y / square) + 1, is dark when i + j is even).

#include <Eigen/Core>
#include <string>
#include <vector>

#include "core/image.h"

namespace confluent {

// A planar checkerboard: inner-corner grid and square size.
struct CheckerboardSpec {
  int cols = 8;            // inner corners along a row (board x)
  int rows = 6;            // inner corners along a column (board y)
  double square_m = 0.1;   // side of one square, metres

  int num_corners() const { return cols * rows; }
  // True when the pattern is symmetric under a half turn (cols + rows even).
  bool half_turn_symmetric() const { return (cols + rows) % 2 == 0; }
  // Corner positions in the board frame (z = 0), metres, in the order described above.
  std::vector<Eigen::Vector3d> CornersInBoard() const;
  // Throws UsageError unless cols >= 2, rows >= 2 and square_m is positive and finite.
  void Check() const;
};

// Parses "8x6" into cols and rows. Throws UsageError on anything else.
void ParseBoardSize(const std::string& text, int* cols, int* rows);

// Options of DetectCheckerboard.
struct CheckerboardDetectOptions {
  // Try OpenCV's classic detector (findChessboardCorners, fast, with a quick rejection of
  // images without a board).
  bool try_classic = true;
  // Then, if that failed, the sector-based detector (findChessboardCornersSB): slower, but it
  // finds small, blurred and oblique boards the classic one misses.
  bool try_sector_based = true;
  // Then, if that failed, the sector-based detector on copies stretched vertically by 2, 3 and
  // 4: a board lying on the floor, seen at a grazing angle, is foreshortened vertically so much
  // that neither detector finds it as it is (utrecht_4cam cam1 needs 2x). Such corners are
  // refined in the stretched frame, and keep the sector detector's refinement where the model
  // fit (below) cannot fit every corner.
  bool try_vertical_stretch = true;
  // With try_vertical_stretch: last, a copy scaled by 1.5 horizontally and 4.5 vertically, for
  // a board that is also small (utrecht_4cam cam4: ~8 px per square across, 3-4 px between
  // rows). Off by default: it costs several seconds on every frame without a board.
  bool try_magnified_stretch = false;
  // Half size of the cornerSubPix search window, pixels; 0 = from the corner spacing.
  int subpix_half_window_px = 0;
  // Images wider than this are detected on a downscaled copy first (then refined at full
  // resolution); 0 disables.
  int max_detection_width_px = 1280;
  // Reject a detection whose smallest corner spacing is below this many pixels.
  double min_corner_spacing_px = 4.0;
  // Final refinement: fit an ideal blurred X-junction (two straight edges through the corner,
  // two grey levels, edge blur) to the pixels around each corner by Levenberg-Marquardt.
  // cv::cornerSubPix alone leaves ~0.06 px RMS of position-dependent error on sharp,
  // anti-aliased corners; the fit brings it to ~0.01-0.02 px. false = cornerSubPix only.
  bool model_refinement = true;
  // With model_refinement: reject a detection in which more corners than this fail the fit
  // (no X-junction found near them: a misplaced grid, a corner hidden or washed out).
  int max_unfitted_corners = 0;

  // Throws UsageError on negative values.
  void Check() const;
};

// Finds all inner corners of `board` in `image` (any channel count and pixel type) with
// subpixel accuracy. Returns false when the whole board is not found. On success,
// `corners_px` has board.num_corners() pixel positions in the canonical order (see top).
bool DetectCheckerboard(const Image& image, const CheckerboardSpec& board,
                        const CheckerboardDetectOptions& options,
                        std::vector<Eigen::Vector2d>* corners_px);

// Reorders a detection by a half turn of the board: index i <-> num_corners - 1 - i.
void HalfTurnCorners(std::vector<Eigen::Vector2d>* corners_px);

}  // namespace confluent
