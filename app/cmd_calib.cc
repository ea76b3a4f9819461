// confluent calib convert: imports another calibration format and writes intri.yml/extri.yml, or
// a Pose2Sim TOML calibration.

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

#include "app/commands.h"
#include "calib/easymocap_io.h"
#include "calib/importers.h"
#include "calib/pose2sim_io.h"
#include "core/error.h"

namespace confluent::app {
namespace {

// "m", "dm", "cm", "mm" or a positive number of metres per unit.
double ParseUnits(const std::string& units) {
  if (units == "m") return 1.0;
  if (units == "dm") return 0.1;
  if (units == "cm") return 0.01;
  if (units == "mm") return 0.001;
  char* end = nullptr;
  const double value = std::strtod(units.c_str(), &end);
  if (!units.empty() && end == units.c_str() + units.size() && value > 0.0) return value;
  throw UsageError("--units: expected m, dm, cm, mm or metres per unit, got '" + units + "'");
}

// Where `--to pose2sim` writes: OUT itself when it names a .toml file, else OUT/Calib.toml.
std::string Pose2SimPath(const std::string& out) {
  const std::filesystem::path path(out);
  return path.extension() == ".toml" ? out : (path / "Calib.toml").string();
}

int RunCalibConvert(const ParsedArgs& args, const Context& /*context*/) {
  const CalibFormat format = ParseCalibFormat(args.get("from"));
  const std::string to = args.get("to", "easymocap");
  if (to != "easymocap" && to != "pose2sim")
    throw UsageError("--to: expected easymocap or pose2sim, got '" + to + "'");
  ImportOptions options;
  if (args.has("units")) options.metres_per_unit = ParseUnits(args.get("units"));
  options.up_axis = args.get("up", "+z");
  RotationToZUp(options.up_axis);  // a bad axis is a usage error before any file is read
  options.default_width = args.get_int("width", 0);
  options.default_height = args.get_int("height", 0);
  if (options.default_width < 0 || options.default_height < 0 || (options.default_width > 0) != (options.default_height > 0))
    throw UsageError("--width and --height must be given together, as positive numbers");

  const std::string input = args.get("input");
  const std::string out = args.get("out");
  const Rig rig = ImportCalibration(format, input, options);
  if (to == "pose2sim") {
    WritePose2SimToml(rig, Pose2SimPath(out));
    std::printf("%d camera(s) from %s -> %s\n", rig.size(), input.c_str(), Pose2SimPath(out).c_str());
  } else {
    WriteEasyMocap(rig, out);
    std::printf("%d camera(s) from %s -> %s/intri.yml, extri.yml\n", rig.size(), input.c_str(), out.c_str());
  }
  std::printf("  %-12s %11s %10s %17s %27s\n", "camera", "size", "fx (px)", "principal point", "centre in world (m)");
  for (const auto& camera : rig.cameras) {
    const Eigen::Vector3d center = camera.center_in_world();
    const std::string size = std::to_string(camera.width) + "x" + std::to_string(camera.height);
    std::printf("  %-12s %11s %10.2f %8.1f %8.1f %8.3f %8.3f %8.3f\n", camera.name.c_str(), size.c_str(),
                camera.K(0, 0), camera.K(0, 2), camera.K(1, 2), center.x(), center.y(), center.z());
  }
  return 0;
}

}  // namespace

CommandSpec MakeCalibConvertCommand() {
  CommandSpec spec;
  spec.name = "calib convert";
  spec.summary = "convert a calibration (COLMAP, transforms.json, Qualisys, Pose2Sim, ...) to intri.yml/extri.yml or Pose2Sim TOML";
  spec.usage = "--from FORMAT --input PATH --out DIR [--to easymocap|pose2sim] [--units m|dm|cm|mm] [--up AXIS] [--width W --height H]";
  spec.description =
      "FORMAT is one of:\n"
      "  easymocap   folder with intri.yml and extri.yml\n"
      "  colmap      folder with cameras.txt and images.txt (one image per camera; names from image names)\n"
      "  transforms  nerfstudio/Blender transforms.json (OpenGL camera-to-world; names from file_path)\n"
      "  qualisys    Qualisys .qca.txt (millimetres unless --units)\n"
      "  plain       per-camera blocks: index, K 3x3, k1 k2, [R|t] 3x4 (size 1024x768 unless --width/--height)\n"
      "  opencv-xml  OpenCV XML/YAML with CameraMatrix, DistortionCoeffs, rvec/tvec (or Rotation/Translation),\n"
      "              one file, or a folder of camera folders (millimetres unless --units)\n"
      "  pose2sim    Pose2Sim TOML (Calib_*.toml): size, matrix, distortions, Rodrigues rotation, translation (m)\n"
      "--to pose2sim writes a Pose2Sim TOML instead of intri.yml/extri.yml: OUT when it ends in .toml, else\n"
      "OUT/Calib.toml.\n"
      "--units gives the unit of the file's translations; the output is in metres. --up names the file's up\n"
      "axis (+z, -z, +y, -y, +x, -x); the rig is rotated so that it becomes +z. --width/--height give the image\n"
      "size where the format does not store it. The result is checked like a native calibration.";
  spec.options = {
      {"from", "FORMAT", "input format (see above)", false, true},
      {"input", "PATH", "input file or folder", false, true},
      {"out", "DIR", "output folder for intri.yml and extri.yml (or the .toml file with --to pose2sim)", false, true},
      {"to", "FORMAT", "output format: easymocap (default) or pose2sim"},
      {"units", "U", "unit of the input translations: m, dm, cm, mm (default: the format's own)"},
      {"up", "AXIS", "the input world's up axis (default +z)"},
      {"width", "W", "image width where the format stores none"},
      {"height", "H", "image height where the format stores none"},
  };
  spec.run = RunCalibConvert;
  return spec;
}

}  // namespace confluent::app
