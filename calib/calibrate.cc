// Multi-camera checkerboard calibration: CalibrateRig chains per-camera intrinsics
// (calibrate_intrinsics.cc), pairwise extrinsic consensus (calibrate_extrinsics.cc) and the joint
// adjustment (bundle_adjustment.cc); board detection over image folders and videos.

#include "calib/calibrate.h"

#include <ceres/rotation.h>

#include <Eigen/SVD>
#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <limits>
#include <map>
#include <set>

#include "calib/calibrate_internal.h"
#include "core/error.h"
#include "core/image_io.h"
#include "core/video.h"

namespace confluent {

void CalibrateOptions::Check() const {
  const std::string owner = "CalibrateOptions.";
  RequireOption(reference_camera >= 0, owner + "reference_camera", reference_camera, ">= 0");
  RequireOption(max_intrinsic_views >= 1, owner + "max_intrinsic_views", max_intrinsic_views, ">= 1");
  RequireOption(distinct_view_px >= 0.0, owner + "distinct_view_px", distinct_view_px, ">= 0");
  RequireOption(min_views_full_model >= 1, owner + "min_views_full_model", min_views_full_model, ">= 1");
  RequireOption(outlier_factor > 1.0, owner + "outlier_factor", outlier_factor, "> 1");
  RequireOption(outlier_min_rms_px >= 0.0, owner + "outlier_min_rms_px", outlier_min_rms_px, ">= 0");
  RequireOption(consensus_rotation_deg > 0.0 && consensus_rotation_deg < 90.0, owner + "consensus_rotation_deg",
                consensus_rotation_deg, "in (0, 90)");
  RequireOption(min_shared_frames >= 1, owner + "min_shared_frames", min_shared_frames, ">= 1");
  RequireOption(max_joint_frames >= 1, owner + "max_joint_frames", max_joint_frames, ">= 1");
  RequireOption(huber_px > 0.0, owner + "huber_px", huber_px, "> 0");
  RequireOption(max_iterations >= 0, owner + "max_iterations", max_iterations, ">= 0");
  RequireOption(num_threads >= 1, owner + "num_threads", num_threads, ">= 1");
}

namespace calibrate_internal {

// ---------------------------------------------------------------------------------------------
// Small pose helpers.

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

}  // namespace calibrate_internal

namespace {

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

using namespace calibrate_internal;

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
