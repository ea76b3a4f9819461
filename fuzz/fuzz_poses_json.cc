// libFuzzer target: tracking/motion_io.h ReadPosesJson, which reads both a run's poses.json and
// the tracker's resumable one-frame state files (tracking/<frame>.json, read by
// pipeline/run_stages_capture.cc). Camera names are given, as when resuming, so the per-camera
// overlaps are parsed too.
#include "fuzz/fuzz_util.h"
#include "tracking/motion_io.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace confluent;
  static const BodyTemplate body;
  static const std::vector<std::string> camera_names = {"cam0", "cam1"};
  const std::string path = fuzz::WriteScratch("poses.json", fuzz::Bytes(data, size));
  fuzz::ExpectTypedErrors([&] { ReadPosesJson(path, body, camera_names); });
  return 0;
}
