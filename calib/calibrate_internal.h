// Internal to calib/: the working state and the steps of CalibrateRig (calibrate.cc), shared by
// calibrate_intrinsics.cc (per-camera intrinsics and view poses), calibrate_extrinsics.cc
// (pairwise extrinsic consensus for the spanning tree) and bundle_adjustment.cc (the joint Ceres
// adjustment). Not part of the module's interface.
#pragma once

#include <ceres/rotation.h>

#include <Eigen/Geometry>
#include <array>
#include <cmath>
#include <map>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "calib/calibrate.h"

namespace confluent {
namespace calibrate_internal {

constexpr double kDeg = M_PI / 180.0;

// ---------------------------------------------------------------------------------------------
// Projection model shared by the adjustment and the error reports.
// intrinsics: fx fy cx cy k1 k2 p1 p2 k3. pose blocks: angle-axis (3) + translation (3).

template <typename T>
void ProjectBoardPoint(const T* intrinsics, const T* cam_from_world, const T* world_from_board, const T* point_in_board,
                       T* pixel) {
  T point_in_world[3];
  ceres::AngleAxisRotatePoint(world_from_board, point_in_board, point_in_world);
  for (int i = 0; i < 3; ++i) point_in_world[i] += world_from_board[3 + i];
  T p[3];
  ceres::AngleAxisRotatePoint(cam_from_world, point_in_world, p);
  for (int i = 0; i < 3; ++i) p[i] += cam_from_world[3 + i];
  const T x = p[0] / p[2], y = p[1] / p[2];
  const T r2 = x * x + y * y;
  const T radial = T(1) + r2 * (intrinsics[4] + r2 * (intrinsics[5] + r2 * intrinsics[8]));
  const T xd = x * radial + T(2) * intrinsics[6] * x * y + intrinsics[7] * (r2 + T(2) * x * x);
  const T yd = y * radial + intrinsics[6] * (r2 + T(2) * y * y) + T(2) * intrinsics[7] * x * y;
  pixel[0] = intrinsics[0] * xd + intrinsics[2];
  pixel[1] = intrinsics[1] * yd + intrinsics[3];
}

// ---------------------------------------------------------------------------------------------
// Small pose helpers (calibrate.cc).

using Pose = Eigen::Isometry3d;

void PoseToBlock(const Pose& pose, double* block);
Pose BlockToPose(const double* block);
double RotationAngleDeg(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b);
Eigen::Matrix3d ProjectToRotation(const Eigen::Matrix3d& m);
// The board's half turn as a board-from-board transform: corner k <-> corner N-1-k.
Pose HalfTurn(const CheckerboardSpec& board);
std::vector<cv::Point3f> CvBoardPoints(const CheckerboardSpec& board);
std::vector<cv::Point2f> CvPixels(const std::vector<Eigen::Vector2d>& pixels);
double Median(std::vector<double> values);

// ---------------------------------------------------------------------------------------------
// Working state.

struct ViewState {
  int frame = 0;
  std::vector<Eigen::Vector2d> corners;
  Pose cam_from_board = Pose::Identity();
  bool has_pose = false;
  bool rejected = false;
  bool selected_for_intrinsics = false;
};

struct CameraState {
  std::string name;
  int width = 0, height = 0;
  double intrinsics[9] = {0, 0, 0, 0, 0, 0, 0, 0, 0};
  bool has_intrinsics = false;
  bool known_intrinsics = false;
  bool reduced_model = false;
  std::vector<ViewState> views;
  std::map<int, int> view_of_frame;  // frame -> index into views (usable views only)
  Pose world_from_cam = Pose::Identity();
  bool placed = false;
  int depth = 0;  // in the spanning tree
};

// Per-camera steps (calibrate_intrinsics.cc).

// RMS reprojection error (pixels) of one view given intrinsics and cam_from_board.
double ViewRms(const CheckerboardSpec& board, const double* intrinsics, const Pose& cam_from_board,
               const std::vector<Eigen::Vector2d>& corners);
// Farthest-point selection of distinct views (at least `distinct_px` apart), starting from the
// view whose corners span the largest area; at most `max_views`.
std::vector<int> SelectViews(const std::vector<ViewState>& views, int max_views, double distinct_px);
// Per-camera calibration with OpenCV. Fills intrinsics, poses of the used views, the report.
void CalibrateIntrinsics(const CheckerboardSpec& board, const CalibrateOptions& options, CameraState* camera,
                         CameraCalibrationReport* report);
// PnP for every view that has no pose yet; rejects views far worse than the typical one.
void PoseAllViews(const CheckerboardSpec& board, const CalibrateOptions& options, CameraState* camera);

// ---------------------------------------------------------------------------------------------
// Extrinsics: pairwise consensus and the spanning tree.

struct Edge {
  int a = -1, b = -1;
  int weight = 0;                       // consistent shared frames
  Pose a_from_b = Pose::Identity();
};

// The consensus a_from_b of two cameras over the frames both saw (calibrate_extrinsics.cc).
Edge PairConsensus(const CameraState& a, const CameraState& b, int index_a, int index_b, const Pose& turn,
                   double rotation_deg);

// ---------------------------------------------------------------------------------------------
// Joint adjustment.

struct Observation {
  int camera = 0;
  int view = 0;
  int frame = 0;
};

struct AdjustmentResult {
  double initial_rms = 0.0, final_rms = 0.0;
  int iterations = 0;
  bool converged = false;
};

// The joint adjustment (bundle_adjustment.cc); with `solve` false only the RMS is measured.
AdjustmentResult Adjust(const CheckerboardSpec& board, const CalibrateOptions& options,
                        const std::vector<Observation>& observations, std::vector<CameraState>* cameras,
                        std::vector<std::array<double, 6>>* camera_blocks, std::map<int, std::array<double, 6>>* boards,
                        bool solve);

}  // namespace calibrate_internal
}  // namespace confluent
