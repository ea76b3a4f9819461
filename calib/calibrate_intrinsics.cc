// Per-camera intrinsics for CalibrateRig: distinct-view selection, OpenCV calibration with
// outlier rounds, and PnP board poses for every usable view.

#include <algorithm>
#include <cmath>
#include <limits>
#include <opencv2/calib3d.hpp>

#include "calib/calibrate_internal.h"

namespace confluent {
namespace calibrate_internal {

namespace {

cv::Mat CvCameraMatrix(const double* intrinsics) {
  cv::Mat k = cv::Mat::eye(3, 3, CV_64F);
  k.at<double>(0, 0) = intrinsics[0];
  k.at<double>(1, 1) = intrinsics[1];
  k.at<double>(0, 2) = intrinsics[2];
  k.at<double>(1, 2) = intrinsics[3];
  return k;
}

cv::Mat CvDist(const double* intrinsics) {
  cv::Mat d(1, 5, CV_64F);
  for (int i = 0; i < 5; ++i) d.at<double>(0, i) = intrinsics[4 + i];
  return d;
}

Pose PoseFromCv(const cv::Mat& rvec, const cv::Mat& tvec) {
  double block[6];
  for (int i = 0; i < 3; ++i) {
    block[i] = rvec.at<double>(i);
    block[3 + i] = tvec.at<double>(i);
  }
  return BlockToPose(block);
}

}  // namespace

// RMS reprojection error (pixels) of one view given intrinsics and cam_from_board.
double ViewRms(const CheckerboardSpec& board, const double* intrinsics, const Pose& cam_from_board,
               const std::vector<Eigen::Vector2d>& corners) {
  double cam_block[6], board_block[6] = {0, 0, 0, 0, 0, 0};
  PoseToBlock(cam_from_board, cam_block);
  const std::vector<Eigen::Vector3d> points = board.CornersInBoard();
  double sum = 0.0;
  for (std::size_t k = 0; k < points.size(); ++k) {
    double pixel[2];
    ProjectBoardPoint(intrinsics, cam_block, board_block, points[k].data(), pixel);
    sum += (Eigen::Vector2d(pixel[0], pixel[1]) - corners[k]).squaredNorm();
  }
  return std::sqrt(sum / points.size());
}

namespace {

// Board pose by PnP (IPPE, then Levenberg-Marquardt refinement).
bool SolveViewPose(const CheckerboardSpec& board, const double* intrinsics, ViewState* view) {
  const std::vector<cv::Point3f> object = CvBoardPoints(board);
  const std::vector<cv::Point2f> image = CvPixels(view->corners);
  const cv::Mat k = CvCameraMatrix(intrinsics), dist = CvDist(intrinsics);
  cv::Mat rvec, tvec;
  if (!cv::solvePnP(object, image, k, dist, rvec, tvec, false, cv::SOLVEPNP_IPPE)) return false;
  cv::solvePnPRefineLM(object, image, k, dist, rvec, tvec);
  view->cam_from_board = PoseFromCv(rvec, tvec);
  view->has_pose = view->cam_from_board.translation().z() > 0.0;
  return view->has_pose;
}

// RMS distance between the corners of two views, pixels.
double ViewDistance(const ViewState& a, const ViewState& b) {
  double sum = 0.0;
  for (std::size_t k = 0; k < a.corners.size(); ++k) sum += (a.corners[k] - b.corners[k]).squaredNorm();
  return std::sqrt(sum / a.corners.size());
}

}  // namespace

// Farthest-point selection of distinct views (at least `distinct_px` apart), starting from the
// view whose corners span the largest area; at most `max_views`.
std::vector<int> SelectViews(const std::vector<ViewState>& views, int max_views, double distinct_px) {
  std::vector<int> selected;
  if (views.empty()) return selected;
  int first = 0;
  double best_area = -1.0;
  for (int i = 0; i < static_cast<int>(views.size()); ++i) {
    Eigen::Vector2d lo = views[i].corners[0], hi = lo;
    for (const auto& c : views[i].corners) {
      lo = lo.cwiseMin(c);
      hi = hi.cwiseMax(c);
    }
    const double area = (hi - lo).prod();
    if (area > best_area) {
      best_area = area;
      first = i;
    }
  }
  std::vector<double> min_distance(views.size(), std::numeric_limits<double>::infinity());
  int next = first;
  while (static_cast<int>(selected.size()) < max_views) {
    selected.push_back(next);
    double farthest = -1.0;
    int candidate = -1;
    for (int i = 0; i < static_cast<int>(views.size()); ++i) {
      min_distance[i] = std::min(min_distance[i], ViewDistance(views[i], views[next]));
      if (min_distance[i] > farthest) {
        farthest = min_distance[i];
        candidate = i;
      }
    }
    if (candidate < 0 || farthest <= distinct_px) break;
    next = candidate;
  }
  std::sort(selected.begin(), selected.end());
  return selected;
}

// Per-camera calibration with OpenCV. Fills intrinsics, poses of the used views, the report.
void CalibrateIntrinsics(const CheckerboardSpec& board, const CalibrateOptions& options, CameraState* camera,
                         CameraCalibrationReport* report) {
  std::vector<int> selected = SelectViews(camera->views, std::numeric_limits<int>::max(), options.distinct_view_px);
  report->views_distinct = static_cast<int>(selected.size());
  if (selected.empty()) return;
  if (static_cast<int>(selected.size()) > options.max_intrinsic_views)
    selected = SelectViews(camera->views, options.max_intrinsic_views, options.distinct_view_px);
  camera->reduced_model = static_cast<int>(selected.size()) < options.min_views_full_model;

  const std::vector<cv::Point3f> object = CvBoardPoints(board);
  const cv::Size size(camera->width, camera->height);
  int flags = 0;
  cv::Mat k = cv::Mat::eye(3, 3, CV_64F), dist = cv::Mat::zeros(1, 5, CV_64F);
  if (camera->reduced_model) {
    std::vector<std::vector<cv::Point3f>> objects;
    std::vector<std::vector<cv::Point2f>> images;
    for (int i : selected) {
      objects.push_back(object);
      images.push_back(CvPixels(camera->views[i].corners));
    }
    const cv::Mat guess = cv::initCameraMatrix2D(objects, images, size);
    const double focal = 0.5 * (guess.at<double>(0, 0) + guess.at<double>(1, 1));
    k.at<double>(0, 0) = k.at<double>(1, 1) = focal > 0 ? focal : std::max(size.width, size.height);
    k.at<double>(0, 2) = 0.5 * (size.width - 1);
    k.at<double>(1, 2) = 0.5 * (size.height - 1);
    flags = cv::CALIB_USE_INTRINSIC_GUESS | cv::CALIB_FIX_PRINCIPAL_POINT | cv::CALIB_FIX_ASPECT_RATIO |
            cv::CALIB_ZERO_TANGENT_DIST | cv::CALIB_FIX_K2 | cv::CALIB_FIX_K3;
  } else {
    if (!options.estimate_k3) flags |= cv::CALIB_FIX_K3;
    if (!options.estimate_tangential) flags |= cv::CALIB_ZERO_TANGENT_DIST;
  }

  double rms = 0.0;
  std::vector<cv::Mat> rvecs, tvecs;
  for (int round = 0; round < 4; ++round) {
    std::vector<std::vector<cv::Point3f>> objects;
    std::vector<std::vector<cv::Point2f>> images;
    for (int i : selected) {
      objects.push_back(object);
      images.push_back(CvPixels(camera->views[i].corners));
    }
    cv::Mat std_intrinsics, std_extrinsics, per_view;
    cv::Mat k_round = k.clone(), dist_round = dist.clone();
    rms = cv::calibrateCamera(objects, images, size, k_round, dist_round, rvecs, tvecs, std_intrinsics, std_extrinsics,
                              per_view, flags,
                              cv::TermCriteria(cv::TermCriteria::COUNT + cv::TermCriteria::EPS, 100, 1e-12));
    k_round.copyTo(k);
    dist_round.reshape(1, 1).colRange(0, 5).copyTo(dist);
    std::vector<double> errors(per_view.begin<double>(), per_view.end<double>());
    const double threshold = std::max(options.outlier_factor * Median(errors), options.outlier_min_rms_px);
    std::vector<int> kept;
    for (std::size_t i = 0; i < selected.size(); ++i)
      if (errors[i] <= threshold) kept.push_back(selected[i]);
      else camera->views[selected[i]].rejected = true;
    if (kept.size() == selected.size()) break;
    const int minimum = camera->reduced_model ? 1 : 3;
    if (static_cast<int>(kept.size()) < minimum) {  // keep the views rather than fail
      for (int i : selected) camera->views[i].rejected = false;
      break;
    }
    selected = kept;
  }
  camera->intrinsics[0] = k.at<double>(0, 0);
  camera->intrinsics[1] = k.at<double>(1, 1);
  camera->intrinsics[2] = k.at<double>(0, 2);
  camera->intrinsics[3] = k.at<double>(1, 2);
  for (int i = 0; i < 5; ++i) camera->intrinsics[4 + i] = dist.at<double>(0, i);
  camera->has_intrinsics = std::isfinite(rms) && camera->intrinsics[0] > 0 && camera->intrinsics[1] > 0;
  for (std::size_t i = 0; i < selected.size(); ++i) {
    camera->views[selected[i]].selected_for_intrinsics = true;
    camera->views[selected[i]].cam_from_board = PoseFromCv(rvecs[i], tvecs[i]);
    camera->views[selected[i]].has_pose = true;
  }
  report->views_intrinsics = static_cast<int>(selected.size());
  report->intrinsic_rms_px = rms;
}

// PnP for every view that has no pose yet; rejects views far worse than the typical one.
void PoseAllViews(const CheckerboardSpec& board, const CalibrateOptions& options, CameraState* camera) {
  std::vector<double> errors;
  for (ViewState& view : camera->views) {
    if (view.rejected) continue;
    if (!view.has_pose && !SolveViewPose(board, camera->intrinsics, &view)) {
      view.rejected = true;
      continue;
    }
    errors.push_back(ViewRms(board, camera->intrinsics, view.cam_from_board, view.corners));
  }
  const double threshold = std::max(options.outlier_factor * Median(errors), options.outlier_min_rms_px);
  for (ViewState& view : camera->views)
    if (!view.rejected && ViewRms(board, camera->intrinsics, view.cam_from_board, view.corners) > threshold)
      view.rejected = true;
  camera->view_of_frame.clear();
  for (int i = 0; i < static_cast<int>(camera->views.size()); ++i)
    if (!camera->views[i].rejected && camera->views[i].has_pose) camera->view_of_frame[camera->views[i].frame] = i;
}

}  // namespace calibrate_internal
}  // namespace confluent
