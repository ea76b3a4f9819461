#pragma once
// Importers of other calibration formats into a Rig (then written as EasyMocap).

#include <Eigen/Core>
#include <string>

#include "calib/camera.h"

namespace confluent {

enum class CalibFormat {
  kEasyMocap,       // directory with intri.yml + extri.yml
  kColmap,          // directory (or cameras.txt path) with cameras.txt + images.txt
  kTransformsJson,  // nerfstudio / Blender transforms.json (camera-to-world, OpenGL axes)
  kQualisys,        // Qualisys .qca.txt XML (mm)
  kPlainText,       // per-camera blocks: index, K 3x3, k1 k2, [R|t] 3x4 (tsinghua_lkB style)
  kOpenCvXml,       // OpenCV FileStorage XML with CameraMatrix, DistortionCoeffs, rvec/tvec
  kPose2Sim,        // Pose2Sim TOML (Calib_*.toml): K, distortions, Rodrigues rvec/tvec (metres)
};

// Parses "easymocap", "colmap", "transforms", "qualisys", "plain", "opencv-xml", "pose2sim".
// Throws UsageError listing the accepted names.
CalibFormat ParseCalibFormat(const std::string& name);

// Options applied after reading, before Check().
struct ImportOptions {
  // Metres per unit of the file's translations (1 = metres, 0.001 = mm, 0.01 = cm,
  // 0.1 = dm). 0 means "the format's documented default" (mm for Qualisys and OpenCV XML,
  // metres for the others).
  double metres_per_unit = 0.0;
  // Which world axis of the file points up: "+z" (no change), "+y", "-y", "-z", "+x", "-x".
  // The rig is rotated so that this axis becomes +z.
  std::string up_axis = "+z";
  // Image size for formats that do not store it (plain text: default 1024x768; OpenCV XML and
  // transforms.json without a size: else read from an image or video beside the file).
  int default_width = 0;
  int default_height = 0;
};

// Reads a calibration in `format` from `input_path`, applies `options` and checks the rig.
// Throws InputError naming the file and the problem.
Rig ImportCalibration(CalibFormat format, const std::string& input_path,
                      const ImportOptions& options = {});

// Rotation that takes the given up axis ("+y", ...) to +z. Throws UsageError on bad names.
Eigen::Matrix3d RotationToZUp(const std::string& up_axis);

}  // namespace confluent
