// Internal to calib/: the helpers the calibration importers share (defined in importers.cc) and
// the per-format readers ImportCalibration dispatches to: COLMAP (importers_colmap.cc),
// transforms.json (importers_transforms_json.cc), Qualisys (importers_qualisys.cc), plain text
// (importers_plain_text.cc) and OpenCV XML/YAML (importers_opencv_xml.cc). Not part of the
// module's interface.
#pragma once

#include <Eigen/Core>
#include <filesystem>
#include <string>
#include <vector>

#include "calib/camera.h"
#include "calib/importers.h"

namespace confluent {
namespace importers_internal {

namespace fs = std::filesystem;

// Parses a whole token as a finite double; throws InputError naming `what` otherwise.
double ParseNumber(const std::string& token, const std::string& path, const std::string& what);

int ParseInt(const std::string& token, const std::string& path, const std::string& what);

std::vector<std::string> SplitWhitespace(const std::string& line);

std::string Lower(std::string text);

// Camera names must be usable as EasyMocap YAML keys: other characters become '_'.
std::string SanitizeName(const std::string& name);

// Camera names from image paths: the file stems, or the parent folder names when the stems
// repeat (e.g. "cam01/000000.png"). Throws InputError when neither is unique.
std::vector<std::string> NamesFromImagePaths(const std::vector<std::string>& image_paths, const std::string& path);

Eigen::Matrix3d IntrinsicMatrix(double fx, double fy, double cx, double cy, double skew = 0.0);

// Rotation nearest to `matrix` (SVD), so that rounding in text files does not fail Check().
// Matrices that are far from a rotation are left alone for Check() to reject.
Eigen::Matrix3d Orthonormalize(const Eigen::Matrix3d& matrix);

// Size of the first image or video found in `folder`, or false.
bool ProbeMediaSize(const fs::path& folder, int* width, int* height);

// Fills a missing image size from the options; throws InputError when there is none.
void ApplyDefaultSize(Camera* camera, const ImportOptions& options, const std::string& path);

Rig ReadColmap(const std::string& input_path);
Rig ReadTransformsJson(const std::string& input_path, const ImportOptions& options);
Rig ReadQualisys(const std::string& path);
Rig ReadPlainText(const std::string& path, const ImportOptions& options);
Rig ReadOpenCvXml(const std::string& input_path, const ImportOptions& options);

}  // namespace importers_internal
}  // namespace confluent
