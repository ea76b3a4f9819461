// confluent calibrate: multi-camera calibration from checkerboard images or videos.

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "app/commands.h"
#include "calib/calibrate.h"
#include "calib/easymocap_io.h"
#include "core/atomic_file.h"
#include "core/error.h"

namespace confluent::app {
namespace fs = std::filesystem;

namespace {

std::string Lower(std::string text) {
  std::transform(text.begin(), text.end(), text.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return text;
}

// Camera subfolders of an --images folder, sorted by name.
std::vector<std::string> CameraFolders(const std::string& dir) {
  std::error_code error;
  if (!fs::is_directory(dir, error)) throw InputError(dir, "no such folder (--images)");
  std::vector<std::string> folders;
  for (const auto& entry : fs::directory_iterator(dir, error))
    if (entry.is_directory()) folders.push_back(entry.path().string());
  std::sort(folders.begin(), folders.end());
  if (folders.empty()) throw InputError(dir, "holds no camera subfolders (one folder of images per camera)");
  return folders;
}

// Videos of a --videos folder, sorted by name.
std::vector<std::string> CameraVideos(const std::string& dir) {
  std::error_code error;
  if (!fs::is_directory(dir, error)) throw InputError(dir, "no such folder (--videos)");
  std::vector<std::string> videos;
  for (const auto& entry : fs::directory_iterator(dir, error)) {
    const std::string extension = Lower(entry.path().extension().string());
    if (entry.is_regular_file() && (extension == ".mp4" || extension == ".avi" || extension == ".mov" ||
                                    extension == ".mkv" || extension == ".webm"))
      videos.push_back(entry.path().string());
  }
  std::sort(videos.begin(), videos.end());
  if (videos.empty()) throw InputError(dir, "holds no videos (mp4, avi, mov, mkv, webm; one per camera)");
  return videos;
}

int RunCalibrate(const ParsedArgs& args, const Context& context) {
  CheckerboardSpec board;
  ParseBoardSize(args.get("board"), &board.cols, &board.rows);
  board.square_m = args.get_double("square-mm", 0.0) / 1000.0;
  if (!(board.square_m > 0.0)) throw UsageError("--square-mm: must be positive");
  const int sources = args.has("images") + args.has("videos") + (args.has("video") ? 1 : 0);
  if (sources != 1) throw UsageError("give exactly one of --images DIR, --videos DIR or --video NAME=FILE...");
  const int stride = args.get_int("stride", 1);
  if (stride < 1) throw UsageError("--stride: must be >= 1");
  const std::string out_dir = args.get("out");

  CalibrateOptions options;
  options.max_intrinsic_views = args.get_int("max-views", options.max_intrinsic_views);
  options.refine_known_intrinsics = args.has("refine-intrinsics");
  options.bundle_adjust = !args.has("no-bundle-adjustment");
  const std::string world = args.get("world", "camera");
  if (world == "board") {
    options.world = CalibrationWorld::kBoard;
    options.world_board_frame = args.get_int("world-frame", -1);
  } else if (world != "camera") {
    throw UsageError("--world: expected 'camera' or 'board', got '" + world + "'");
  }
  options.Check();

  // Detection, camera by camera.
  ProgressCallback progress = context.make_progress();
  CheckerboardDetectOptions detect;
  detect.try_magnified_stretch = args.has("small-boards");
  std::vector<CameraBoardViews> views;
  if (args.has("images")) {
    for (const std::string& folder : CameraFolders(args.get("images")))
      views.push_back(DetectBoardInImages(folder, board, detect, stride, progress));
  } else if (args.has("videos")) {
    for (const std::string& video : CameraVideos(args.get("videos")))
      views.push_back(DetectBoardInVideo(video, board, detect, stride, progress));
  } else {
    for (const std::string& item : args.get_all("video")) {
      const std::size_t eq = item.find('=');
      if (eq == std::string::npos || eq == 0 || eq + 1 == item.size())
        throw UsageError("--video: expected NAME=FILE, got '" + item + "'");
      CameraBoardViews camera_views = DetectBoardInVideo(item.substr(eq + 1), board, detect, stride, progress);
      camera_views.name = item.substr(0, eq);
      views.push_back(std::move(camera_views));
    }
  }

  // Known intrinsics, matched by camera name.
  if (args.has("intrinsics")) {
    const fs::path dir = args.get("intrinsics");
    const Rig known = ReadEasyMocap((dir / "intri.yml").string(), (dir / "extri.yml").string());
    for (CameraBoardViews& camera_views : views) {
      const int index = known.IndexOf(camera_views.name);
      if (index < 0) throw InputError((dir / "intri.yml").string(), "has no camera " + camera_views.name);
      camera_views.known_intrinsics = known.cameras[index];
    }
  }

  if (args.has("reference-camera")) {
    const std::string name = args.get("reference-camera");
    auto found = std::find_if(views.begin(), views.end(), [&](const CameraBoardViews& v) { return v.name == name; });
    if (found == views.end()) {
      std::string names;
      for (const auto& v : views) names += (names.empty() ? "" : ", ") + v.name;
      throw UsageError("--reference-camera " + name + ": no such camera (cameras: " + names + ")");
    }
    options.reference_camera = static_cast<int>(found - views.begin());
  }

  CalibrationSummary summary;
  const Rig rig = CalibrateRig(board, views, options, &summary, progress);

  std::printf("%-14s %7s %7s %9s %8s %8s %13s %12s  %s\n", "camera", "frames", "boards", "distinct", "used",
              "rejected", "intrinsic RMS", "final RMS px", "placed");
  nlohmann::json report;
  for (const CameraCalibrationReport& r : summary.cameras) {
    std::printf("%-14s %7d %7d %9d %8d %8d %13.3f %12.3f  %s%s\n", r.name.c_str(), r.frames_searched, r.views_detected,
                r.views_distinct, r.views_in_adjustment, r.views_rejected, r.intrinsic_rms_px, r.final_rms_px,
                r.placed ? "yes" : "NO", r.reduced_model ? "  (f and k1 only: too few distinct views)" : "");
    report["cameras"][r.name] = {{"frames_searched", r.frames_searched}, {"views_detected", r.views_detected},
                                 {"views_distinct", r.views_distinct},   {"views_intrinsics", r.views_intrinsics},
                                 {"views_rejected", r.views_rejected},   {"views_in_adjustment", r.views_in_adjustment},
                                 {"intrinsic_rms_px", r.intrinsic_rms_px}, {"final_rms_px", r.final_rms_px},
                                 {"reduced_model", r.reduced_model},     {"placed", r.placed}};
  }
  std::printf("joint RMS %.3f px (before adjustment %.3f px) over %d board poses; %d half-turn fixes\n",
              summary.final_rms_px, summary.initial_rms_px, summary.joint_frames, summary.half_turns);
  report["joint_rms_px"] = summary.final_rms_px;
  report["initial_rms_px"] = summary.initial_rms_px;
  report["board_poses"] = summary.joint_frames;
  report["board"] = {{"cols", board.cols}, {"rows", board.rows}, {"square_m", board.square_m}};

  if (summary.status == CalibrationStatus::kFailed)
    throw Error("calibration failed: reference camera " + rig.cameras[options.reference_camera].name +
                " could not be calibrated; " + summary.message);
  // Only calibrated and placed cameras are written.
  Rig placed;
  for (int c = 0; c < rig.size(); ++c)
    if (summary.cameras[c].placed) placed.cameras.push_back(rig.cameras[c]);
  WriteEasyMocap(placed, out_dir);
  WriteTextFile((fs::path(out_dir) / "calibration_report.json").string(), report.dump(2));
  std::printf("wrote %s/intri.yml and extri.yml (%d cameras)\n", out_dir.c_str(), placed.size());
  if (summary.status == CalibrationStatus::kPartial) throw Error(summary.message);
  return 0;
}

}  // namespace

CommandSpec MakeCalibrateCommand() {
  CommandSpec spec;
  spec.name = "calibrate";
  spec.summary = "calibrate cameras from checkerboard images or videos (writes intri.yml/extri.yml)";
  spec.usage =
      "--board COLSxROWS --square-mm S (--images DIR | --videos DIR | --video NAME=FILE...) --out DIR "
      "[--reference-camera NAME] [--stride N] [--max-views N]";
  spec.description =
      "COLSxROWS counts the board's inner corners. --images DIR holds one folder of images per camera; --videos\n"
      "DIR one video per camera; the camera name is the folder name or the file stem. Images with the same\n"
      "position in name order (video frames with the same index) are taken as simultaneous.\n"
      "Per camera: subpixel corners, views chosen for coverage, cv::calibrateCamera with outlier views rejected.\n"
      "Extrinsics: relative poses from boards seen by several cameras at once, chained from the reference camera\n"
      "along the camera graph, then a joint Ceres bundle adjustment of all cameras and board poses.\n"
      "Prints a per-camera table and writes DIR/intri.yml, DIR/extri.yml and DIR/calibration_report.json.\n"
      "Exit status 1 if some camera could not be calibrated or placed (the others are still written).";
  spec.options = {
      {"board", "COLSxROWS", "inner corners of the checkerboard, e.g. 8x6", false, true},
      {"square-mm", "S", "side of one square in millimetres", false, true},
      {"images", "DIR", "one subfolder of images per camera"},
      {"videos", "DIR", "one video per camera"},
      {"video", "NAME=FILE", "a camera's video (repeat for each camera)", true},
      {"out", "DIR", "output folder for intri.yml / extri.yml", false, true},
      {"reference-camera", "NAME", "camera whose frame is the world (default: the first)"},
      {"stride", "N", "use every N-th image or frame (default 1)"},
      {"max-views", "N", "views per camera for the intrinsic calibration (default 40)"},
      {"intrinsics", "DIR", "known intrinsics: DIR/intri.yml + extri.yml, matched by camera name"},
      {"refine-intrinsics", "", "let the bundle adjustment refine --intrinsics"},
      {"world", "camera|board", "world frame: the reference camera (default) or a board pose"},
      {"world-frame", "N", "with --world board: the frame whose board is the world (default: most seen)"},
      {"no-bundle-adjustment", "", "skip the joint adjustment (chained initial poses only)"},
      {"small-boards", "", "also search a magnified, stretched copy for small grazing boards (slow on frames without a board)"},
  };
  spec.run = RunCalibrate;
  return spec;
}

}  // namespace confluent::app
