#pragma once
// Multi-camera calibration from checkerboard views: per-camera intrinsics (Zhang 2000, through
// OpenCV), extrinsics chained through a camera graph, and a joint bundle adjustment (Ceres).

#include <optional>
#include <string>
#include <vector>

#include "calib/camera.h"
#include "calib/checkerboard.h"
#include "core/progress.h"

namespace confluent {

// One detection of the whole board by one camera.
struct BoardView {
  int frame = 0;                             // frame index; equal indices are simultaneous
  std::vector<Eigen::Vector2d> corners_px;   // num_corners() pixels, checkerboard.h order
};

// Everything one camera saw.
struct CameraBoardViews {
  std::string name;
  int width = 0;   // image size, pixels
  int height = 0;
  int frames_searched = 0;        // frames looked at (for the summary)
  std::vector<BoardView> views;   // frames in which the board was found
  // Known intrinsics (K and dist are used, the pose is ignored), e.g. from an earlier
  // calibration. When set, the per-camera intrinsic calibration is skipped.
  std::optional<Camera> known_intrinsics;
};

// Where the output world frame is.
enum class CalibrationWorld {
  kReferenceCamera,  // the reference camera's frame (identity pose)
  kBoard,            // the board in one frame: origin at corner 0, x along the board's rows,
                     // z out of the board's front face (up for a board lying on the floor)
};

// Options of CalibrateRig.
struct CalibrateOptions {
  int reference_camera = 0;          // index into the input cameras; gauge of the adjustment
  CalibrationWorld world = CalibrationWorld::kReferenceCamera;
  int world_board_frame = -1;        // kBoard: frame whose board defines the world; -1 = the
                                     // frame seen by the most cameras (earliest on ties)
  // Intrinsics.
  int max_intrinsic_views = 40;      // views per camera chosen for coverage (farthest-point)
  double distinct_view_px = 3.0;     // views closer than this (RMS corner motion) count as one
  int min_views_full_model = 6;      // fewer distinct views: only f and k1 are estimated, with
                                     // the principal point at the image centre
  bool estimate_k3 = true;           // radial k3 (else fixed at 0)
  bool estimate_tangential = true;   // p1, p2 (else fixed at 0)
  double outlier_factor = 3.0;       // reject views with RMS > factor x median RMS ...
  double outlier_min_rms_px = 0.3;   // ... and above this floor
  // Extrinsics.
  double consensus_rotation_deg = 10.0;  // relative poses agreeing within this are consistent
  int min_shared_frames = 1;             // camera graph edge: frames seen by both cameras
  // Joint bundle adjustment.
  bool bundle_adjust = true;
  bool refine_known_intrinsics = false;  // also adjust cameras given with known_intrinsics
  int max_joint_frames = 200;            // board poses in the adjustment (most-seen first)
  double huber_px = 1.0;                 // robust loss scale
  int max_iterations = 100;
  int num_threads = 1;

  // Throws UsageError on out-of-range values.
  void Check() const;
};

enum class CalibrationStatus {
  kSuccess,   // every camera calibrated and placed
  kPartial,   // some cameras lack intrinsics or share no views with the rest (see message)
  kFailed,    // the reference camera could not be calibrated
};

// Per-camera figures of a calibration.
struct CameraCalibrationReport {
  std::string name;
  int frames_searched = 0;
  int views_detected = 0;       // frames with the whole board found
  int views_distinct = 0;       // distinct poses among them
  int views_intrinsics = 0;     // views used by the per-camera calibration
  int views_rejected = 0;       // outlier views dropped (per-camera and after adjustment)
  int views_in_adjustment = 0;  // views in the joint bundle adjustment
  double intrinsic_rms_px = 0.0;  // RMS of the per-camera calibration (0 with known intrinsics)
  double final_rms_px = 0.0;      // RMS after the joint adjustment (all its views)
  bool reduced_model = false;     // only f and k1 were estimated (too few distinct views)
  bool has_intrinsics = false;
  bool placed = false;            // has extrinsics (connected to the reference camera)
};

// Result of CalibrateRig.
struct CalibrationSummary {
  CalibrationStatus status = CalibrationStatus::kFailed;
  std::string message;                        // one line: what went wrong, if anything
  std::vector<CameraCalibrationReport> cameras;
  int joint_frames = 0;                       // board poses in the adjustment
  int half_turns = 0;                         // views re-ordered by a half turn for consistency
  double initial_rms_px = 0.0;                // joint RMS before / after the adjustment
  double final_rms_px = 0.0;
  int iterations = 0;
  bool converged = false;
};

// Calibrates every camera of `views` (same order in the result) from checkerboard detections.
// Steps: per camera, frame selection for coverage, cv::calibrateCamera, outlier views rejected
// and recalibrated; per view, the board pose by PnP; camera pairs' relative poses by consensus
// over their shared frames (which also fixes each view's half-turn ambiguity); poses chained
// from the reference camera along a maximum spanning tree (edge weight = shared frames); then a
// Huber-robust joint adjustment of all intrinsics (k1 k2 p1 p2 k3), camera poses and board
// poses with the reference camera fixed. Cameras without intrinsics or not connected to the
// reference keep an identity pose and are flagged in the summary. Throws UsageError on bad
// options or inconsistent input (corner counts, sizes).
Rig CalibrateRig(const CheckerboardSpec& board, const std::vector<CameraBoardViews>& views,
                 const CalibrateOptions& options, CalibrationSummary* summary,
                 const ProgressCallback& progress = {});

// Detects the board in every `stride`-th image of `dir` (files sorted by name; frame = index in
// that order). name = the folder's name. Throws InputError naming the folder when it is missing
// or holds no images, or naming an unreadable image.
CameraBoardViews DetectBoardInImages(const std::string& dir, const CheckerboardSpec& board,
                                     const CheckerboardDetectOptions& options, int stride = 1,
                                     const ProgressCallback& progress = {});

// Detects the board in every `stride`-th frame of a video (frame = frame index). name = the
// file's stem. Throws InputError naming the file when it cannot be decoded.
CameraBoardViews DetectBoardInVideo(const std::string& path, const CheckerboardSpec& board,
                                    const CheckerboardDetectOptions& options, int stride = 1,
                                    const ProgressCallback& progress = {});

}  // namespace confluent
