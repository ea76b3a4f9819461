// Multi-camera checkerboard calibration. The Ceres cost functor (autodiff) lives only in this
// translation unit.

#include "calib/calibrate.h"

#include <ceres/ceres.h>
#include <ceres/rotation.h>

#include <Eigen/SVD>
#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <limits>
#include <map>
#include <numeric>
#include <opencv2/calib3d.hpp>
#include <set>

#include "core/error.h"
#include "core/image_io.h"
#include "core/video.h"

namespace confluent {

void CalibrateOptions::Check() const {
  auto fail = [](const std::string& what) { throw UsageError("CalibrateOptions: " + what); };
  if (reference_camera < 0) fail("reference_camera must be >= 0");
  if (max_intrinsic_views < 1) fail("max_intrinsic_views must be >= 1");
  if (!(distinct_view_px >= 0.0)) fail("distinct_view_px must be >= 0");
  if (min_views_full_model < 1) fail("min_views_full_model must be >= 1");
  if (!(outlier_factor > 1.0)) fail("outlier_factor must be > 1");
  if (!(outlier_min_rms_px >= 0.0)) fail("outlier_min_rms_px must be >= 0");
  if (!(consensus_rotation_deg > 0.0 && consensus_rotation_deg < 90.0)) fail("consensus_rotation_deg must be in (0, 90)");
  if (min_shared_frames < 1) fail("min_shared_frames must be >= 1");
  if (max_joint_frames < 1) fail("max_joint_frames must be >= 1");
  if (!(huber_px > 0.0)) fail("huber_px must be > 0");
  if (max_iterations < 0) fail("max_iterations must be >= 0");
  if (num_threads < 1) fail("num_threads must be >= 1");
}

namespace {

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

struct CornerResidual {
  CornerResidual(const Eigen::Vector3d& point_in_board, const Eigen::Vector2d& observed_px)
      : point_(point_in_board), observed_(observed_px) {}
  template <typename T>
  bool operator()(const T* intrinsics, const T* cam_from_world, const T* world_from_board, T* residual) const {
    const T point[3] = {T(point_.x()), T(point_.y()), T(point_.z())};
    T pixel[2];
    ProjectBoardPoint(intrinsics, cam_from_world, world_from_board, point, pixel);
    residual[0] = pixel[0] - T(observed_.x());
    residual[1] = pixel[1] - T(observed_.y());
    return true;
  }
  Eigen::Vector3d point_;
  Eigen::Vector2d observed_;
};

// ---------------------------------------------------------------------------------------------
// Small pose helpers.

using Pose = Eigen::Isometry3d;

void PoseToBlock(const Pose& pose, double* block) {
  const Eigen::Matrix3d rotation = pose.linear();
  ceres::RotationMatrixToAngleAxis(ceres::ColumnMajorAdapter3x3(rotation.data()), block);
  for (int i = 0; i < 3; ++i) block[3 + i] = pose.translation()[i];
}

Pose BlockToPose(const double* block) {
  Eigen::Matrix3d rotation;
  ceres::AngleAxisToRotationMatrix(block, ceres::ColumnMajorAdapter3x3(rotation.data()));
  Pose pose = Pose::Identity();
  pose.linear() = rotation;
  pose.translation() = Eigen::Vector3d(block[3], block[4], block[5]);
  return pose;
}

double RotationAngleDeg(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b) {
  const double c = std::clamp(0.5 * ((a.transpose() * b).trace() - 1.0), -1.0, 1.0);
  return std::acos(c) / kDeg;
}

Eigen::Matrix3d ProjectToRotation(const Eigen::Matrix3d& m) {
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(m, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d d = Eigen::Matrix3d::Identity();
  d(2, 2) = (svd.matrixU() * svd.matrixV().transpose()).determinant() < 0 ? -1.0 : 1.0;
  return svd.matrixU() * d * svd.matrixV().transpose();
}

// The board's half turn as a board-from-board transform: corner k <-> corner N-1-k.
Pose HalfTurn(const CheckerboardSpec& board) {
  Pose turn = Pose::Identity();
  turn.linear() = Eigen::Vector3d(-1.0, -1.0, 1.0).asDiagonal();
  turn.translation() = Eigen::Vector3d((board.cols - 1) * board.square_m, (board.rows - 1) * board.square_m, 0.0);
  return turn;
}

std::vector<cv::Point3f> CvBoardPoints(const CheckerboardSpec& board) {
  std::vector<cv::Point3f> points;
  for (const Eigen::Vector3d& p : board.CornersInBoard())
    points.emplace_back(static_cast<float>(p.x()), static_cast<float>(p.y()), static_cast<float>(p.z()));
  return points;
}

std::vector<cv::Point2f> CvPixels(const std::vector<Eigen::Vector2d>& pixels) {
  std::vector<cv::Point2f> out;
  out.reserve(pixels.size());
  for (const auto& p : pixels) out.emplace_back(static_cast<float>(p.x()), static_cast<float>(p.y()));
  return out;
}

double Median(std::vector<double> values) {
  if (values.empty()) return 0.0;
  const std::size_t mid = values.size() / 2;
  std::nth_element(values.begin(), values.begin() + mid, values.end());
  return values[mid];
}

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

// ---------------------------------------------------------------------------------------------
// Extrinsics: pairwise consensus and the spanning tree.

struct Edge {
  int a = -1, b = -1;
  int weight = 0;                       // consistent shared frames
  Pose a_from_b = Pose::Identity();
};

bool PosesAgree(const Pose& x, const Pose& y, double rotation_deg) {
  if (RotationAngleDeg(x.linear(), y.linear()) > rotation_deg) return false;
  const double scale = std::max({x.translation().norm(), y.translation().norm(), 1e-6});
  return (x.translation() - y.translation()).norm() <= 0.2 * scale;
}

Edge PairConsensus(const CameraState& a, const CameraState& b, int index_a, int index_b, const Pose& turn,
                   double rotation_deg) {
  Edge edge;
  edge.a = index_a;
  edge.b = index_b;
  std::vector<std::array<Pose, 2>> candidates;
  for (const auto& [frame, view_a] : a.view_of_frame) {
    const auto found = b.view_of_frame.find(frame);
    if (found == b.view_of_frame.end()) continue;
    const Pose& pose_a = a.views[view_a].cam_from_board;
    const Pose& pose_b = b.views[found->second].cam_from_board;
    candidates.push_back({pose_a * pose_b.inverse(), pose_a * turn * pose_b.inverse()});
  }
  if (candidates.empty()) return edge;
  int best_count = -1, best_plain = -1;
  std::vector<int> best_choice;
  for (std::size_t f = 0; f < candidates.size(); ++f)
    for (int d = 0; d < 2; ++d) {
      std::vector<int> choice(candidates.size(), -1);
      int count = 0, plain = 0;
      for (std::size_t g = 0; g < candidates.size(); ++g)
        for (int e = 0; e < 2; ++e)
          if (PosesAgree(candidates[g][e], candidates[f][d], rotation_deg)) {
            choice[g] = e;
            ++count;
            plain += e == 0;
            break;
          }
      if (count > best_count || (count == best_count && plain > best_plain)) {
        best_count = count;
        best_plain = plain;
        best_choice = choice;
      }
    }
  Eigen::Matrix3d rotation_sum = Eigen::Matrix3d::Zero();
  Eigen::Vector3d translation_sum = Eigen::Vector3d::Zero();
  for (std::size_t g = 0; g < candidates.size(); ++g)
    if (best_choice[g] >= 0) {
      rotation_sum += candidates[g][best_choice[g]].linear();
      translation_sum += candidates[g][best_choice[g]].translation();
    }
  edge.weight = best_count;
  edge.a_from_b.linear() = ProjectToRotation(rotation_sum);
  edge.a_from_b.translation() = translation_sum / best_count;
  return edge;
}

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

AdjustmentResult Adjust(const CheckerboardSpec& board, const CalibrateOptions& options,
                        const std::vector<Observation>& observations, std::vector<CameraState>* cameras,
                        std::vector<std::array<double, 6>>* camera_blocks, std::map<int, std::array<double, 6>>* boards,
                        bool solve) {
  const std::vector<Eigen::Vector3d> points = board.CornersInBoard();
  ceres::HuberLoss loss(options.huber_px);  // shared by every residual block
  ceres::Problem::Options problem_options;
  problem_options.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  problem_options.manifold_ownership = ceres::TAKE_OWNERSHIP;
  ceres::Problem problem(problem_options);
  std::set<int> used_cameras;
  for (const Observation& o : observations) {
    CameraState& camera = (*cameras)[o.camera];
    const ViewState& view = camera.views[o.view];
    for (std::size_t k = 0; k < points.size(); ++k) {
      auto* cost = new ceres::AutoDiffCostFunction<CornerResidual, 2, 9, 6, 6>(new CornerResidual(points[k], view.corners[k]));
      problem.AddResidualBlock(cost, &loss, camera.intrinsics,
                               (*camera_blocks)[o.camera].data(), (*boards)[o.frame].data());
    }
    used_cameras.insert(o.camera);
  }
  for (int c : used_cameras) {
    CameraState& camera = (*cameras)[c];
    if (c == options.reference_camera) problem.SetParameterBlockConstant((*camera_blocks)[c].data());
    if ((camera.known_intrinsics && !options.refine_known_intrinsics) || camera.reduced_model) {
      problem.SetParameterBlockConstant(camera.intrinsics);
    } else {
      std::vector<int> fixed;
      if (!options.estimate_tangential) {
        fixed.push_back(6);
        fixed.push_back(7);
      }
      if (!options.estimate_k3) fixed.push_back(8);
      if (!fixed.empty()) problem.SetManifold(camera.intrinsics, new ceres::SubsetManifold(9, fixed));
    }
  }
  AdjustmentResult result;
  auto rms = [&]() {
    double sum = 0.0;
    std::size_t count = 0;
    for (const Observation& o : observations) {
      const CameraState& camera = (*cameras)[o.camera];
      const ViewState& view = camera.views[o.view];
      for (std::size_t k = 0; k < points.size(); ++k) {
        double pixel[2];
        ProjectBoardPoint(camera.intrinsics, (*camera_blocks)[o.camera].data(), (*boards)[o.frame].data(),
                          points[k].data(), pixel);
        sum += (Eigen::Vector2d(pixel[0], pixel[1]) - view.corners[k]).squaredNorm();
        ++count;
      }
    }
    return count ? std::sqrt(sum / count) : 0.0;
  };
  result.initial_rms = rms();
  if (solve && !observations.empty()) {
    ceres::Solver::Options solver_options;
    solver_options.linear_solver_type = ceres::DENSE_SCHUR;
    solver_options.max_num_iterations = options.max_iterations;
    solver_options.num_threads = options.num_threads;
    solver_options.function_tolerance = 1e-12;
    solver_options.gradient_tolerance = 1e-14;
    solver_options.parameter_tolerance = 1e-12;
    solver_options.logging_type = ceres::SILENT;
    ceres::Solver::Summary solver_summary;
    ceres::Solve(solver_options, &problem, &solver_summary);
    result.iterations = static_cast<int>(solver_summary.iterations.size());
    result.converged = solver_summary.termination_type == ceres::CONVERGENCE;
  }
  result.final_rms = rms();
  return result;
}

std::vector<std::string> ImageFilesIn(const std::string& dir) {
  namespace fs = std::filesystem;
  std::error_code error;
  if (!fs::is_directory(dir, error)) throw InputError(dir, "no such folder");
  static const std::set<std::string> kExtensions = {".png", ".jpg", ".jpeg", ".bmp", ".tif", ".tiff", ".exr", ".pgm", ".ppm"};
  std::vector<std::string> files;
  for (const auto& entry : fs::directory_iterator(dir, error)) {
    if (!entry.is_regular_file()) continue;
    std::string extension = entry.path().extension().string();
    std::transform(extension.begin(), extension.end(), extension.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    if (kExtensions.count(extension)) files.push_back(entry.path().string());
  }
  std::sort(files.begin(), files.end());
  if (files.empty()) throw InputError(dir, "folder holds no images (png, jpg, bmp, tif, exr)");
  return files;
}

}  // namespace

// -----------------------------------------------------------------------------------------------

Rig CalibrateRig(const CheckerboardSpec& board, const std::vector<CameraBoardViews>& views,
                 const CalibrateOptions& options, CalibrationSummary* summary, const ProgressCallback& progress) {
  board.Check();
  options.Check();
  if (views.empty()) throw UsageError("calibrate: no cameras given");
  if (options.reference_camera >= static_cast<int>(views.size()))
    throw UsageError("calibrate: reference camera index " + std::to_string(options.reference_camera) + " but only " +
                     std::to_string(views.size()) + " cameras");
  *summary = CalibrationSummary();
  const int num_cameras = static_cast<int>(views.size());
  std::vector<CameraState> cameras(num_cameras);
  summary->cameras.resize(num_cameras);

  // 1. Input and per-camera intrinsics.
  for (int c = 0; c < num_cameras; ++c) {
    const CameraBoardViews& input = views[c];
    CameraState& camera = cameras[c];
    CameraCalibrationReport& report = summary->cameras[c];
    camera.name = report.name = input.name;
    camera.width = input.width;
    camera.height = input.height;
    if (camera.width <= 0 || camera.height <= 0)
      throw UsageError("calibrate: camera " + input.name + " has no image size");
    report.frames_searched = input.frames_searched;
    report.views_detected = static_cast<int>(input.views.size());
    std::set<int> frames;
    for (const BoardView& view : input.views) {
      if (static_cast<int>(view.corners_px.size()) != board.num_corners())
        throw UsageError("calibrate: camera " + input.name + " frame " + std::to_string(view.frame) + " has " +
                         std::to_string(view.corners_px.size()) + " corners, the board has " +
                         std::to_string(board.num_corners()));
      if (!frames.insert(view.frame).second)
        throw UsageError("calibrate: camera " + input.name + " has two views of frame " + std::to_string(view.frame));
      ViewState state;
      state.frame = view.frame;
      state.corners = view.corners_px;
      camera.views.push_back(std::move(state));
    }
    ReportProgress(progress, "intrinsics", c, num_cameras, input.name);
    if (input.known_intrinsics) {
      const Camera& known = *input.known_intrinsics;
      camera.intrinsics[0] = known.K(0, 0);
      camera.intrinsics[1] = known.K(1, 1);
      camera.intrinsics[2] = known.K(0, 2);
      camera.intrinsics[3] = known.K(1, 2);
      for (int i = 0; i < 5; ++i) camera.intrinsics[4 + i] = known.dist[i];
      camera.has_intrinsics = camera.known_intrinsics = true;
      report.views_distinct = static_cast<int>(SelectViews(camera.views, std::numeric_limits<int>::max(),
                                                           options.distinct_view_px).size());
    } else {
      CalibrateIntrinsics(board, options, &camera, &report);
    }
    report.reduced_model = camera.reduced_model;
    report.has_intrinsics = camera.has_intrinsics;
    if (camera.has_intrinsics) PoseAllViews(board, options, &camera);
  }
  ReportProgress(progress, "intrinsics", num_cameras, num_cameras);

  // 2. Camera graph and spanning tree from the reference camera.
  const Pose turn = HalfTurn(board);
  std::vector<Edge> edges;
  for (int a = 0; a < num_cameras; ++a)
    for (int b = a + 1; b < num_cameras; ++b) {
      if (!cameras[a].has_intrinsics || !cameras[b].has_intrinsics) continue;
      Edge edge = PairConsensus(cameras[a], cameras[b], a, b, turn, options.consensus_rotation_deg);
      if (edge.weight >= options.min_shared_frames) edges.push_back(edge);
    }
  ReportProgress(progress, "extrinsics", 0, 1);
  const int ref = options.reference_camera;
  if (cameras[ref].has_intrinsics) {
    cameras[ref].placed = true;
    cameras[ref].world_from_cam = Pose::Identity();
    for (;;) {  // Prim: heaviest edge from the tree to a new camera
      const Edge* best = nullptr;
      for (const Edge& edge : edges)
        if (cameras[edge.a].placed != cameras[edge.b].placed && (best == nullptr || edge.weight > best->weight))
          best = &edge;
      if (best == nullptr) break;
      if (cameras[best->a].placed) {
        cameras[best->b].world_from_cam = cameras[best->a].world_from_cam * best->a_from_b;
        cameras[best->b].depth = cameras[best->a].depth + 1;
        cameras[best->b].placed = true;
      } else {
        cameras[best->a].world_from_cam = cameras[best->b].world_from_cam * best->a_from_b.inverse();
        cameras[best->a].depth = cameras[best->b].depth + 1;
        cameras[best->a].placed = true;
      }
    }
  }

  // 3. Board pose per frame, and each view's half turn made consistent with it.
  std::map<int, std::vector<int>> observers;  // frame -> placed cameras that see it
  for (int c = 0; c < num_cameras; ++c)
    if (cameras[c].placed)
      for (const auto& [frame, view] : cameras[c].view_of_frame) observers[frame].push_back(c);
  std::map<int, Pose> world_from_board;
  for (auto& [frame, list] : observers) {
    const int anchor = *std::min_element(list.begin(), list.end(), [&](int x, int y) {
      return std::make_pair(cameras[x].depth, x) < std::make_pair(cameras[y].depth, y);
    });
    const Pose anchor_pose = cameras[anchor].world_from_cam * cameras[anchor].views[cameras[anchor].view_of_frame[frame]].cam_from_board;
    world_from_board[frame] = anchor_pose;
    std::vector<int> kept;
    for (int c : list) {
      ViewState& view = cameras[c].views[cameras[c].view_of_frame[frame]];
      const Pose plain = cameras[c].world_from_cam * view.cam_from_board;
      const double angle_plain = RotationAngleDeg(plain.linear(), anchor_pose.linear());
      const double angle_turned = RotationAngleDeg((plain * turn).linear(), anchor_pose.linear());
      if (std::min(angle_plain, angle_turned) > 3.0 * options.consensus_rotation_deg) {
        view.rejected = true;  // inconsistent with the other cameras in this frame
        cameras[c].view_of_frame.erase(frame);
        continue;
      }
      if (angle_turned < angle_plain) {
        HalfTurnCorners(&view.corners);
        view.cam_from_board = view.cam_from_board * turn;
        ++summary->half_turns;
      }
      kept.push_back(c);
    }
    list = kept;
  }
  ReportProgress(progress, "extrinsics", 1, 1);

  // 4. Frames for the joint adjustment: the most-seen multi-camera frames, plus every camera's
  //    intrinsic views.
  std::vector<std::pair<int, int>> multi;  // (-observers, frame)
  for (const auto& [frame, list] : observers)
    if (list.size() >= 2) multi.emplace_back(-static_cast<int>(list.size()), frame);
  std::sort(multi.begin(), multi.end());
  std::set<int> joint_frames;
  for (std::size_t i = 0; i < multi.size() && static_cast<int>(i) < options.max_joint_frames; ++i)
    joint_frames.insert(multi[i].second);
  for (const CameraState& camera : cameras)
    if (camera.placed)
      for (const auto& [frame, view] : camera.view_of_frame)
        if (camera.views[view].selected_for_intrinsics) joint_frames.insert(frame);

  std::vector<std::array<double, 6>> camera_blocks(num_cameras);
  for (int c = 0; c < num_cameras; ++c) PoseToBlock(cameras[c].world_from_cam.inverse(), camera_blocks[c].data());
  std::map<int, std::array<double, 6>> board_blocks;
  for (int frame : joint_frames) PoseToBlock(world_from_board[frame], board_blocks[frame].data());
  auto collect = [&]() {
    std::vector<Observation> observations;
    for (int frame : joint_frames)
      for (int c : observers[frame]) {
        const auto found = cameras[c].view_of_frame.find(frame);
        if (found != cameras[c].view_of_frame.end() && !cameras[c].views[found->second].rejected)
          observations.push_back({c, found->second, frame});
      }
    return observations;
  };

  ReportProgress(progress, "bundle adjustment", 0, 2);
  std::vector<Observation> observations = collect();
  AdjustmentResult result = Adjust(board, options, observations, &cameras, &camera_blocks, &board_blocks, options.bundle_adjust);
  summary->initial_rms_px = result.initial_rms;
  // Reject views far worse than the typical one, then adjust again.
  if (options.bundle_adjust) {
    std::vector<double> errors;
    std::vector<double> view_rms(observations.size());
    for (std::size_t i = 0; i < observations.size(); ++i) {
      const Observation& o = observations[i];
      const Pose cam_from_board = BlockToPose(camera_blocks[o.camera].data()) * BlockToPose(board_blocks[o.frame].data());
      view_rms[i] = ViewRms(board, cameras[o.camera].intrinsics, cam_from_board, cameras[o.camera].views[o.view].corners);
      errors.push_back(view_rms[i]);
    }
    const double threshold = std::max(options.outlier_factor * Median(errors), options.outlier_min_rms_px);
    bool any = false;
    for (std::size_t i = 0; i < observations.size(); ++i)
      if (view_rms[i] > threshold) {
        cameras[observations[i].camera].views[observations[i].view].rejected = true;
        any = true;
      }
    ReportProgress(progress, "bundle adjustment", 1, 2);
    if (any) {
      const double initial = result.initial_rms;
      observations = collect();
      result = Adjust(board, options, observations, &cameras, &camera_blocks, &board_blocks, true);
      result.initial_rms = initial;
    }
  }
  ReportProgress(progress, "bundle adjustment", 2, 2);
  summary->final_rms_px = result.final_rms;
  summary->iterations = result.iterations;
  summary->converged = result.converged;
  summary->joint_frames = static_cast<int>(joint_frames.size());

  // 5. Reports: per-camera RMS over the adjustment's views.
  {
    std::vector<double> sum(num_cameras, 0.0);
    std::vector<int> count(num_cameras, 0);
    for (const Observation& o : observations) {
      const Pose cam_from_board = BlockToPose(camera_blocks[o.camera].data()) * BlockToPose(board_blocks[o.frame].data());
      const double rms = ViewRms(board, cameras[o.camera].intrinsics, cam_from_board, cameras[o.camera].views[o.view].corners);
      sum[o.camera] += rms * rms;
      ++count[o.camera];
    }
    for (int c = 0; c < num_cameras; ++c) {
      CameraCalibrationReport& report = summary->cameras[c];
      report.views_in_adjustment = count[c];
      report.final_rms_px = count[c] ? std::sqrt(sum[c] / count[c]) : report.intrinsic_rms_px;
      report.views_rejected = 0;
      for (const ViewState& view : cameras[c].views) report.views_rejected += view.rejected;
      report.placed = cameras[c].placed;
      report.has_intrinsics = cameras[c].has_intrinsics;
    }
  }

  // 6. The rig, in the requested world frame.
  Pose new_world_from_old = Pose::Identity();
  if (options.world == CalibrationWorld::kBoard) {
    int frame = options.world_board_frame;
    if (frame < 0) {
      if (multi.empty() && observers.empty()) throw UsageError("calibrate: no board pose to define the world frame");
      frame = multi.empty() ? observers.begin()->first : multi.front().second;
    }
    if (!board_blocks.count(frame))
      throw UsageError("calibrate: world board frame " + std::to_string(frame) +
                       " is not a frame in which placed cameras saw the board");
    Pose world_from_board_new = Pose::Identity();
    world_from_board_new.linear() = Eigen::Vector3d(1.0, -1.0, -1.0).asDiagonal();
    new_world_from_old = world_from_board_new * BlockToPose(board_blocks[frame].data()).inverse();
  }
  Rig rig;
  std::vector<std::string> problems;
  for (int c = 0; c < num_cameras; ++c) {
    const CameraState& state = cameras[c];
    Camera camera;
    camera.name = state.name;
    camera.width = state.width;
    camera.height = state.height;
    camera.K << state.intrinsics[0], 0.0, state.intrinsics[2], 0.0, state.intrinsics[1], state.intrinsics[3], 0.0, 0.0, 1.0;
    for (int i = 0; i < 5; ++i) camera.dist[i] = state.intrinsics[4 + i];
    if (!state.has_intrinsics) {
      camera.K = Eigen::Matrix3d::Identity();
      camera.dist.setZero();
      problems.push_back(state.name + " (no intrinsics: " + std::to_string(summary->cameras[c].views_detected) +
                         " board views)");
    } else if (!state.placed) {
      problems.push_back(state.name + " (shares no consistent board views with the reference camera)");
    } else {
      const Pose cam_from_new_world = BlockToPose(camera_blocks[c].data()) * new_world_from_old.inverse();
      camera.rotation = ProjectToRotation(cam_from_new_world.linear());
      camera.translation = cam_from_new_world.translation();
    }
    rig.cameras.push_back(camera);
  }
  if (!cameras[ref].has_intrinsics) {
    summary->status = CalibrationStatus::kFailed;
  } else {
    summary->status = problems.empty() ? CalibrationStatus::kSuccess : CalibrationStatus::kPartial;
  }
  if (!problems.empty()) {
    summary->message = "not calibrated: ";
    for (std::size_t i = 0; i < problems.size(); ++i) summary->message += (i ? ", " : "") + problems[i];
  }
  return rig;
}

CameraBoardViews DetectBoardInImages(const std::string& dir, const CheckerboardSpec& board,
                                     const CheckerboardDetectOptions& options, int stride,
                                     const ProgressCallback& progress) {
  if (stride < 1) throw UsageError("--stride: must be >= 1");
  const std::vector<std::string> files = ImageFilesIn(dir);
  CameraBoardViews result;
  result.name = std::filesystem::path(dir).filename().string();
  if (result.name.empty()) result.name = std::filesystem::path(dir).parent_path().filename().string();
  for (std::size_t i = 0; i < files.size(); i += stride) {
    ReportProgress(progress, "detect " + result.name, i, files.size());
    const Image image = ReadImage(files[i]);
    if (result.width == 0) {
      result.width = image.width;
      result.height = image.height;
    } else if (image.width != result.width || image.height != result.height) {
      throw InputError(files[i], "image is " + std::to_string(image.width) + "x" + std::to_string(image.height) +
                                     ", the folder's first image is " + std::to_string(result.width) + "x" +
                                     std::to_string(result.height));
    }
    ++result.frames_searched;
    BoardView view;
    view.frame = static_cast<int>(i);
    if (DetectCheckerboard(image, board, options, &view.corners_px)) result.views.push_back(std::move(view));
  }
  ReportProgress(progress, "detect " + result.name, files.size(), files.size());
  return result;
}

CameraBoardViews DetectBoardInVideo(const std::string& path, const CheckerboardSpec& board,
                                    const CheckerboardDetectOptions& options, int stride,
                                    const ProgressCallback& progress) {
  if (stride < 1) throw UsageError("--stride: must be >= 1");
  VideoReader reader(path);
  const int count = reader.num_frames();
  if (count <= 0) throw InputError(path, "video has no decodable frames");
  CameraBoardViews result;
  result.name = std::filesystem::path(path).stem().string();
  result.width = reader.width();
  result.height = reader.height();
  for (int i = 0; i < count; i += stride) {
    ReportProgress(progress, "detect " + result.name, i, count);
    const Image image = reader.ReadFrame(i);
    ++result.frames_searched;
    BoardView view;
    view.frame = i;
    if (DetectCheckerboard(image, board, options, &view.corners_px)) result.views.push_back(std::move(view));
  }
  ReportProgress(progress, "detect " + result.name, count, count);
  return result;
}

}  // namespace confluent
