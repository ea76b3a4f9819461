// confluent capture info CAPTURE: validate a recorded camera folder and summarise it.

#include <cstdio>

#include "app/commands.h"
#include "calib/capture.h"

namespace confluent::app {
namespace {

int RunCaptureInfo(const ParsedArgs& args, const Context& context) {
  CaptureOptions options;
  options.check_every_image_header = !args.has("quick");
  options.decode_every_frame = args.has("decode");
  options.progress = context.make_progress();
  const Capture capture = Capture::Open(args.positionals()[0], options);
  std::printf("capture   %s\n", capture.root().c_str());
  std::printf("source    %s\n", capture.source() == FrameSource::kImages ? "images/" : "videos/");
  std::printf("cameras   %d\nframes    %d\n", capture.num_cameras(), capture.num_frames());
  std::printf("masks     %s\n", capture.has_masks() ? "yes" : "no");
  std::printf("scan      %s\n", capture.scan_path().empty() ? "-" : capture.scan_path().c_str());
  std::printf("corresp.  %s\n", capture.correspondences_path().empty() ? "-" : capture.correspondences_path().c_str());
  std::printf("\ncamera        size        fx        fy   background\n");
  for (int c = 0; c < capture.num_cameras(); ++c) {
    const Camera& camera = capture.rig().cameras[c];
    std::printf("%-12s %4dx%-4d %9.1f %9.1f   %s\n", camera.name.c_str(), camera.width, camera.height,
                camera.K(0, 0), camera.K(1, 1), capture.BackgroundPath(c).empty() ? "-" : "yes");
  }
  for (const std::string& warning : capture.warnings()) std::printf("warning: %s\n", warning.c_str());
  return 0;
}

}  // namespace

CommandSpec MakeCaptureInfoCommand() {
  CommandSpec spec;
  spec.name = "capture info";
  spec.summary = "validate a recorded camera folder and list its cameras and frames";
  spec.usage = "CAPTURE [--quick | --decode]";
  spec.description =
      "Checks that intri.yml, extri.yml and images/ (or videos/) agree on the cameras, that every camera has\n"
      "the same number of frames, and that image sizes match the calibration.";
  spec.min_positionals = spec.max_positionals = 1;
  spec.options = {{"quick", "", "check the first and last image of each camera only"},
                  {"decode", "", "fully decode every frame (finds truncated or corrupt images)"}};
  spec.run = RunCaptureInfo;
  return spec;
}

}  // namespace confluent::app
